/*
 * unit_main.h — the main() every unit-test program shares.
 * A test file defines `static Suite *make_suite(void)` and ends with
 * CANFDI_UNIT_MAIN(make_suite). Exit status 0 iff every test passed.
 */
#ifndef CANFDI_UNIT_MAIN_H
#define CANFDI_UNIT_MAIN_H

#include <check.h>
#include <stdlib.h>

#define CANFDI_UNIT_MAIN(suite_fn)                          \
  int main(void)                                            \
  {                                                         \
    SRunner *sr = srunner_create(suite_fn());               \
    srunner_run_all(sr, CK_NORMAL);                         \
    int failed = srunner_ntests_failed(sr);                 \
    srunner_free(sr);                                       \
    return (failed == 0) ? EXIT_SUCCESS : EXIT_FAILURE;     \
  }

#endif
