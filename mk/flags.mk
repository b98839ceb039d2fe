# mk/flags.mk — the compilers and the flags of every build flavour, each
# spelled out once. The Makefile reads this file before any fragment; the
# fragments use these variables and add only what is theirs (an include
# folder for their own sources, a feature macro for one source file).
#
#   flavour        flags                 used for
#   host           HOST_CFLAGS           unit tests, SIL runner, canfdi-sim,
#                                        canfdi-ecu-asan ($(BUILD)/host)
#   host, C11      HOST_C11_CFLAGS       `make unit-c11` ($(BUILD)/unit-c11)
#   host, 32-bit   HOST_M32_CFLAGS       `make unit-m32` ($(BUILD)/unit-m32)
#   UBSan only     UBSAN_CFLAGS          canfdi-ecu for the vcan sandbox
#                                        ($(BUILD)/ubsan)
#   release        REL_CFLAGS            benches, sil-long, canfdi-ecu-rel,
#                                        the signal demo ($(BUILD)/rel)
#   release+UBSan  REL_UBSAN_CFLAGS      canfdi-sim for the vcan sandbox
#   Cortex-M       TGT_ARCH_<core>       `make firmware`, PIL (pil-test,
#                  TGT_CFLAGS, TGT_LDFLAGS,  bench-pil)
#                  PIL_LDFLAGS
#   C++ reference  REF_CXXFLAGS          tests/ref (Eigen)
#
# Per-source flags: SRC_CFLAGS_<source path> (e.g. the libc feature macros
# one file needs) are added by every pattern rule that compiles that source,
# in every flavour. They must come from the command line: HOST_ASSERT
# pre-includes assert.h, which fixes the feature macros before the file
# could define them.

CC := gcc
CXX := g++
ARM_PREFIX ?= arm-none-eabi-
ARM_CC := $(ARM_PREFIX)gcc
ARM_NM := $(ARM_PREFIX)nm
ARM_SIZE := $(ARM_PREFIX)size

# The C standard and the warnings of every C file we build, host or target.
C_STD := -std=c99
WARN := -Wall -Wextra -Werror -pedantic -Wconversion -Wsign-conversion \
        -Wdouble-promotion -Wfloat-equal -Wshadow -Wstrict-prototypes \
        -Wmissing-prototypes -Wundef
WARN_C := $(C_STD) $(WARN)

# Sanitizers: a finding aborts the program. ASan cannot run in the vcan
# sandbox (User-Mode Linux has no room for its shadow memory, mk/ecu.mk),
# so what runs there has UBSan alone.
UBSAN_CHECKS := -fsanitize=undefined -fno-sanitize-recover=all
UBSAN := $(UBSAN_CHECKS) -fno-omit-frame-pointer
SAN := -fsanitize=address $(UBSAN)

# Every firmware build: the firmware root and the generated code.
FW_INC := -Ifirmware -I$(BUILD)/gen
# Host builds that check the firmware's invariants: CANFDI_ASSERT is assert().
HOST_ASSERT := -include assert.h '-DCANFDI_ASSERT(x)=assert(x)'

HOST_CFLAGS := $(WARN_C) -O1 -g $(SAN) $(FW_INC) $(HOST_ASSERT)
UBSAN_CFLAGS := $(WARN_C) -O1 -g $(UBSAN) $(FW_INC) $(HOST_ASSERT)
# As on a target: -O2, no sanitizers, CANFDI_ASSERT off.
REL_CFLAGS := $(WARN_C) -O2 -g $(FW_INC)
REL_UBSAN_CFLAGS := $(REL_CFLAGS) $(UBSAN_CHECKS) $(HOST_ASSERT)

# libcheck, for the unit-test programs.
CHECK_CFLAGS := $(shell pkg-config --cflags check 2>/dev/null)
CHECK_LIBS := $(shell pkg-config --libs check 2>/dev/null || echo -lcheck -lsubunit -lm -lrt -lpthread)
UNIT_CFLAGS := -Itests/unit -Ihost_sim $(CHECK_CFLAGS)

# The unit-test flavours: the host build under C11, and for the 32-bit x86
# ABI (ILP32, like the Cortex-M targets). Debian's libcheck cannot be
# installed for i386 beside the amd64 one (the package is not Multi-Arch),
# so `make deps` unpacks the i386 package's static library into
# $(CHECK_I386_DIR) (tools/deps.sh).
# The C11 flavour also builds the portable forms of what has a compiler
# builtin (core/canfdi_fixp.h), so that both forms are tested.
HOST_C11_CFLAGS := $(patsubst $(C_STD),-std=c11,$(HOST_CFLAGS)) -DCANFDI_FIXP_PORTABLE
HOST_M32_CFLAGS := -m32 $(HOST_CFLAGS)
CHECK_I386_DIR := .deps/check-i386
HOST_M32_LDFLAGS := -m32 -L$(CHECK_I386_DIR)

# Cortex-M: the M4 is treated as the no-FPU variant (soft-float ABI, no VFP
# code); the M0/M0+ (ARMv6-M) have no hardware divide and no 32x32->64
# multiply. The M3 and M0 are the PIL rig's cores (tests/pil); the M4F with
# its FPU builds only the textbook floating-point RLS the RLS bench compares
# with (bench/bench_rls_pil.c), never firmware.
TGT_ABI := -mthumb -mfloat-abi=soft
TGT_ARCH_cortex-m4 := -mcpu=cortex-m4 $(TGT_ABI)
TGT_ARCH_cortex-m3 := -mcpu=cortex-m3 $(TGT_ABI)
TGT_ARCH_cortex-m0 := -mcpu=cortex-m0 $(TGT_ABI)
TGT_ARCH_cortex-m0plus := -mcpu=cortex-m0plus $(TGT_ABI)
TGT_ARCH_cortex-m4f := -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard
TGT_CFLAGS := $(WARN_C) -Os -g -ffunction-sections -fdata-sections $(FW_INC) -I$(BUILD)/target
# Linker scripts: one per board (MEMORY and stack), sharing the section
# layout through INCLUDE, found on -L.
TGT_LDDIR := firmware/port/cortexm
TGT_LDSCRIPT := $(TGT_LDDIR)/canfdi_cortexm.ld
TGT_LDSCRIPT_NRF51 := $(TGT_LDDIR)/canfdi_nrf51.ld
TGT_LDSCRIPTS := $(TGT_LDSCRIPT) $(TGT_LDSCRIPT_NRF51) $(TGT_LDDIR)/canfdi_sections.ld
tgt_link = -nostartfiles -Wl,--gc-sections -Wl,-L,$(TGT_LDDIR) -Wl,-T,$(1)
TGT_LINK := $(call tgt_link,$(TGT_LDSCRIPT))
# The firmware images: newlib-nano, no system calls (a stray malloc links).
TGT_LDFLAGS := --specs=nano.specs --specs=nosys.specs $(TGT_LINK)
# PIL on QEMU: semihosting (rdimon) reads the bus log; a harness, not firmware.
PIL_LDFLAGS := --specs=rdimon.specs $(TGT_LINK)

REF_CXXFLAGS := -std=c++17 -O1 -g -Wall -Wextra -Werror $(SAN) -I/usr/include/eigen3 \
                $(FW_INC) -Ihost_sim -Itests/ref

# `make -s print-VAR` prints the value of VAR, for scripts that build with
# these flags (tests/dbc/conftest.py).
print-%:
	$(info $($*))@:
