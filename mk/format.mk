# mk/format.mk — `make format FILES="a.c b.h ..."`: clang-format rewrites in
# place exactly the C/C++ files named, in the style of .clang-format (the
# firmware's). Nothing else is touched, and `make test` checks no format:
# existing files keep their layout until someone edits them. clang-format
# is installed on first use (tools/deps.sh format), not by `make deps`.

FORMAT_EXT := %.c %.h %.cpp %.hpp

.PHONY: format
format:
	@if [ -z "$(strip $(FILES))" ]; then \
	  echo 'make format: name the files to format: make format FILES="firmware/core/canfdi_fixp.c ..."' >&2; exit 2; fi
	@bad="$(strip $(filter-out $(FORMAT_EXT),$(FILES)))"; if [ -n "$$bad" ]; then \
	  echo "make format: not a C/C++ source or header: $$bad" >&2; exit 2; fi
	@for f in $(FILES); do [ -f "$$f" ] || { echo "make format: no such file: $$f" >&2; exit 2; }; done
	@bash tools/deps.sh format >/dev/null
	clang-format -i --style=file:$(CURDIR)/.clang-format $(FILES)
