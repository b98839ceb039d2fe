# mk/vcan.mk — the vcan sandbox (tools/vcan-run): runs a command where a
# SocketCAN vcan0 exists, directly on a kernel with vcan, else inside
# User-Mode Linux (~2 s of overhead per call). Other fragments run their
# SocketCAN programs through $(VCAN_RUN):
#
#   $(VCAN_RUN) [--timeout S] [--] CMD ARGS...   (CANFDI_VCAN=host|uml forces
#                                                 a mode; see tools/vcan-run --help)
#   make vcan-test    self-test of the sandbox: exit status, stdout/stderr,
#                     arguments, cwd, environment, vcan0 + can-utils +
#                     python-can, --timeout, error messages (~10 s; make test)

VCAN_RUN := $(CURDIR)/tools/vcan-run

.PHONY: vcan-test
vcan-test: deps
	@bash tests/vcan/test_vcan_run.sh

TEST_STEPS += vcan-test
