/*
 * test_flavour.c — the unit-test program was built for the flavour its make
 * target promises (mk/unit.mk): the C standard, and the data model (the
 * widths of pointers and long; the firmware's targets are ILP32). Each
 * flavour passes what it promises as CANFDI_UNIT_STDC, CANFDI_UNIT_PTR_BITS
 * and CANFDI_UNIT_LONG_BITS; a flag lost on the way fails here.
 */
#include <check.h>
#include <limits.h>
#include <stdint.h>

#include "unit_main.h"

#if !defined(CANFDI_UNIT_STDC) || !defined(CANFDI_UNIT_PTR_BITS) || !defined(CANFDI_UNIT_LONG_BITS)
#error "build the unit tests with make (mk/unit.mk defines the flavour's expectations)"
#endif

START_TEST(test_c_standard)
{
  ck_assert_int_eq(__STDC_VERSION__, CANFDI_UNIT_STDC);
}
END_TEST

START_TEST(test_data_model)
{
  ck_assert_uint_eq(sizeof(void *) * CHAR_BIT, CANFDI_UNIT_PTR_BITS);
  ck_assert_uint_eq(sizeof(uintptr_t) * CHAR_BIT, CANFDI_UNIT_PTR_BITS);
  ck_assert_uint_eq(sizeof(long) * CHAR_BIT, CANFDI_UNIT_LONG_BITS);
  /* what the firmware assumes in every flavour */
  ck_assert_uint_eq(sizeof(int) * CHAR_BIT, 32U);
  ck_assert_uint_eq(sizeof(long long) * CHAR_BIT, 64U);
}
END_TEST

static Suite *make_suite(void)
{
  Suite *s = suite_create("flavour");
  TCase *tc = tcase_create("build");
  tcase_add_test(tc, test_c_standard);
  tcase_add_test(tc, test_data_model);
  suite_add_tcase(s, tc);
  return s;
}

CANFDI_UNIT_MAIN(make_suite)
