# Generated model and guidance layer of the flight library (included by the top Makefile).
#   $(BUILD)/generated/tscvx_model.[ch]  CasADi -> C (codegen/generate.py), reproducible
#   $(BUILD)/libtscvx_gnc.a               guidance: SCvx loop, subproblem, guess, FOH, model
#   $(BUILD)/libtscvx_gnc.so              the same + the SOCP runtime (for the Python bindings)
#   $(BUILD)/pdg_example                  plain C example: static libraries + Debian deps only
#   make ctest-gnc                        guidance C tests under valgrind, the landing against
#                                         another hypot (test_libm_hypot) + no-malloc check
#   make ctest-asan-gnc                   the same tests under ASan/UBSan (in make ctest-asan)
#   make budget-gnc                       RAD750 budget table (guidance/budget.py)

GEN_DIR    := $(BUILD)/generated
GNC_OBJDIR := $(BUILD)/obj/gnc
GNC_SRCS   := $(wildcard c_runtime/guidance/*.c)
GNC_HDRS   := $(wildcard c_runtime/guidance/*.h) c_runtime/include/tscvx_guidance.h \
              c_runtime/include/tscvx_socp.h c_runtime/include/tscvx_types.h \
              c_runtime/include/tscvx_nn.h c_runtime/include/tscvx_fnv1a.h
GNC_OBJS   := $(patsubst c_runtime/guidance/%.c,$(GNC_OBJDIR)/%.o,$(GNC_SRCS)) $(GNC_OBJDIR)/tscvx_model.o $(NN_OBJS)
GNC_CFLAGS := $(FLIGHT_CFLAGS) -fPIC -Ic_runtime/include -Ic_runtime/guidance -I$(GEN_DIR)
# static link line of a flight application: guidance, SOCP runtime, SuiteSparse, libm
GNC_LINK   := $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx.a -lamd -lldl -lsuitesparseconfig -lm
GNC_TESTS  := test_guidance test_tscvx

$(GEN_DIR)/tscvx_model.c $(GEN_DIR)/tscvx_model.h &: codegen/generate.py guidance/model.py | $(FLIGHT_STAMP)
	$(PY) codegen/generate.py $(GEN_DIR)
	@touch $(GEN_DIR)/tscvx_model.c $(GEN_DIR)/tscvx_model.h  # the generator keeps identical files untouched

# CasADi's generated entry points share one signature and ignore some arguments, and the
# generated file defines them (and its helpers) without including its header.
$(GNC_OBJDIR)/tscvx_model.o: $(GEN_DIR)/tscvx_model.c $(FLAGS_STAMP)
	@mkdir -p $(GNC_OBJDIR)
	$(CC) $(GNC_CFLAGS) -Wno-unused-parameter -Wno-missing-prototypes -c $< -o $@

$(GNC_OBJDIR)/%.o: c_runtime/guidance/%.c $(GNC_HDRS) $(GEN_DIR)/tscvx_model.h $(FLAGS_STAMP)
	@mkdir -p $(GNC_OBJDIR)
	$(CC) $(GNC_CFLAGS) -c $< -o $@

$(BUILD)/libtscvx_gnc.a: $(GNC_OBJS)
	rm -f $@
	ar rcs $@ $(GNC_OBJS)

$(BUILD)/libtscvx_gnc.so: $(GNC_OBJS) $(CRT_OBJS)
	$(CC) -shared -o $@ $(GNC_OBJS) $(CRT_OBJS) -lamd -lldl -lsuitesparseconfig -lm

$(BUILD)/pdg_example: c_runtime/examples/pdg_example.c c_runtime/examples/host_io.h c_runtime/include/tscvx_guidance.h c_runtime/include/tscvx_nn.h $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx.a
	$(CC) -std=c99 -Wall -Wextra -Werror -O2 -Ic_runtime/include $< -o $@ $(GNC_LINK)

$(BUILD)/pdg_budget_driver: c_runtime/examples/pdg_budget_driver.c c_runtime/examples/measure.h c_runtime/examples/host_io.h c_runtime/include/tscvx_guidance.h c_runtime/include/tscvx_nn.h $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx.a
	$(CC) -std=c99 -Wall -Wextra -Werror -O2 -g -Ic_runtime/include $< -o $@ $(GNC_LINK)

$(BUILD)/ctest/%: c_runtime/guidance/tests/%.c c_runtime/guidance/tests/gnc_test.h c_runtime/include/tscvx_guidance.h c_runtime/examples/host_io.h $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx.a
	@mkdir -p $(BUILD)/ctest
	$(CC) -std=c99 -Wall -Wextra -Werror -O1 -g -Ic_runtime/include -Ic_runtime/examples \
	  -Ic_runtime/guidance -Ic_runtime/src -I$(GEN_DIR) $< -o $@ $(GNC_LINK)

# The default landing with the host's hypot and with one rounding a ulp up (-Wl,--wrap=hypot):
# the same answer to the bit, whatever the libm (run natively by ctest-gnc)
$(BUILD)/ctest/test_libm_hypot: c_runtime/guidance/tests/test_libm_hypot.c c_runtime/guidance/tests/gnc_test.h c_runtime/include/tscvx_guidance.h $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx.a
	@mkdir -p $(BUILD)/ctest
	$(CC) -std=c99 -Wall -Wextra -Werror -O1 -g -Ic_runtime/include $< -o $@ -Wl,--wrap=hypot \
	  $(GNC_LINK)

gnc: $(BUILD)/libtscvx_gnc.a $(BUILD)/libtscvx_gnc.so
lib: gnc
example: $(BUILD)/pdg_example
lib: example

ctest-gnc: lib $(addprefix $(BUILD)/ctest/,$(GNC_TESTS)) $(BUILD)/pdg_budget_driver $(BUILD)/ctest/test_libm_hypot
	@set -e; for t in $(GNC_TESTS); do \
	  echo "== $$t (valgrind)"; valgrind -q --error-exitcode=1 --leak-check=full \
	    --errors-for-leak-kinds=definite $(BUILD)/ctest/$$t; done
	@echo "== test_libm_hypot (the landing whatever libm's hypot, native run)"
	@$(BUILD)/ctest/test_libm_hypot
	@echo "== no heap allocation inside pdg_solve (malloc interposition, native run)"
	@$(BUILD)/pdg_budget_driver | tee $(BUILD)/ctest/pdg_budget_driver.out | grep -q '^heap_allocations_in_solve 0$$' \
	  || { cat $(BUILD)/ctest/pdg_budget_driver.out; echo "heap allocation inside pdg_solve"; exit 1; }
	@echo "== no heap allocation inside pdg_solve_tscvx (both networks, native run)"
	@$(BUILD)/pdg_budget_driver --tscvx $(BUILD)/models/solution.tnn --masks $(BUILD)/models/constraint.tnn \
	  > $(BUILD)/ctest/pdg_budget_driver_tscvx.out; \
	  grep -q '^heap_allocations_in_solve 0$$' $(BUILD)/ctest/pdg_budget_driver_tscvx.out \
	  && grep -q '^mode tscvx_masks$$' $(BUILD)/ctest/pdg_budget_driver_tscvx.out \
	  || { cat $(BUILD)/ctest/pdg_budget_driver_tscvx.out; echo "heap allocation inside pdg_solve_tscvx"; exit 1; }

# The guidance C tests again under AddressSanitizer + UBSan, from the sources (guidance,
# generated model, networks, SOCP runtime; part of `make ctest-asan`).
ctest-asan-gnc: lib
	@mkdir -p $(BUILD)/ctest-asan
	@set -e; for t in $(GNC_TESTS); do \
	  $(CC) -std=c99 -g -O1 -fno-var-tracking-assignments -fsanitize=address,undefined \
	    -fno-sanitize-recover=undefined -Ic_runtime/include -Ic_runtime/examples \
	    -Ic_runtime/guidance -Ic_runtime/src -I$(GEN_DIR) -I/usr/include/suitesparse \
	    c_runtime/guidance/tests/$$t.c $(GNC_SRCS) $(GEN_DIR)/tscvx_model.c $(NN_SRCS) \
	    $(CRT_SRCS) -o $(BUILD)/ctest-asan/$$t -lamd -lldl -lsuitesparseconfig -lm; \
	  echo "== $$t (ASan/UBSan)"; $(BUILD)/ctest-asan/$$t; done
ctest-asan: ctest-asan-gnc

budget-gnc: setup-flight lib $(BUILD)/pdg_budget_driver
	$(PY) -m guidance.budget

.PHONY: gnc example ctest-gnc ctest-asan-gnc budget-gnc
ctest: ctest-gnc
