# mk/nvm.mk — the host NVM port (firmware/port/linux/canfdi_nvm_file.c, a
# file holding both banks of diag/canfdi_nvm). firmware/port/ is not part of
# FW_SRC, so the object is linked into every unit test here (test_nvm uses
# it); it is built by the top Makefile's $(BUILD)/host/%.o rule with
# HOST_CFLAGS (warnings, ASan/UBSan).
#
# The pre-included assert.h fixes the libc feature macros before a source
# file could define them, so POSIX (pread/pwrite/fdatasync; mkdtemp, fork
# and kill in the test) is requested on the command line.

NVM_FILE_OBJ := $(BUILD)/host/firmware/port/linux/canfdi_nvm_file.o

UNIT_EXTRA_OBJ += $(NVM_FILE_OBJ)

$(NVM_FILE_OBJ): HOST_CFLAGS += -D_POSIX_C_SOURCE=200809L
$(BUILD)/unit/test_nvm.o: HOST_CFLAGS += -D_POSIX_C_SOURCE=200809L
