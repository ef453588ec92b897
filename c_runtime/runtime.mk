# Flight C library build rules (included by the top-level Makefile).
lib: apt
	@mkdir -p $(BUILD)

ctest: lib
