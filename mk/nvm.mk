# mk/nvm.mk — the host NVM port (firmware/port/linux/canfdi_nvm_file.c, a
# file holding both banks of diag/canfdi_nvm). firmware/port/ is not part of
# FW_SRC, so the source is linked into every unit test here (test_nvm uses
# it), in every unit-test flavour (mk/unit.mk).
#
# POSIX (pread/pwrite/fdatasync; mkdtemp, fork and kill in the test) is
# requested on the command line, per source (SRC_CFLAGS_, mk/flags.mk).

NVM_FILE_SRC := firmware/port/linux/canfdi_nvm_file.c
NVM_FILE_OBJ := $(NVM_FILE_SRC:%.c=$(BUILD)/host/%.o)

UNIT_EXTRA_SRC += $(NVM_FILE_SRC)

SRC_CFLAGS_$(NVM_FILE_SRC) := -D_POSIX_C_SOURCE=200809L
SRC_CFLAGS_tests/unit/test_nvm.c := -D_POSIX_C_SOURCE=200809L
