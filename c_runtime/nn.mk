# Network inference of the flight library (included by the top Makefile, before guidance.mk,
# which links $(NN_OBJS) into libtscvx_gnc.a / .so).
#   $(BUILD)/models/{constraint,solution}.tnn  weight files from models/*.onnx
#                                              (guidance/nn/flight.py; same ONNX, same bytes)
#   $(BUILD)/nn_budget_driver                  one tscvx_nn_run, for callgrind (guidance/budget.py)
#   make ctest-nn                              C tests under valgrind + no-malloc check
#
# Compiled with the flight flags (FLIGHT_CFLAGS, top Makefile: scalar FPU, no vectorizer).

NN_OBJDIR  := $(BUILD)/obj/nn
NN_SRCS    := $(wildcard c_runtime/nn/*.c)
NN_HDRS    := $(wildcard c_runtime/nn/*.h) c_runtime/include/tscvx_nn.h c_runtime/include/tscvx_fnv1a.h
NN_OBJS    := $(patsubst c_runtime/nn/%.c,$(NN_OBJDIR)/%.o,$(NN_SRCS))
NN_CFLAGS  := $(FLIGHT_CFLAGS) -fPIC -Ic_runtime/include
NN_MODELS  := $(BUILD)/models/constraint.tnn $(BUILD)/models/solution.tnn
NN_TESTS   := test_nn

$(NN_OBJDIR)/%.o: c_runtime/nn/%.c $(NN_HDRS) $(FLAGS_STAMP)
	@mkdir -p $(NN_OBJDIR)
	$(CC) $(NN_CFLAGS) -c $< -o $@

$(BUILD)/models/%.tnn: models/%.onnx guidance/nn/flight.py guidance/nn/infer.py | $(FLIGHT_STAMP)
	$(PY) -m guidance.nn.flight $< $@
	@touch $@  # the writer keeps an identical file untouched

$(BUILD)/nn_budget_driver: c_runtime/nn/tests/nn_budget_driver.c c_runtime/examples/measure.h c_runtime/examples/host_io.h c_runtime/include/tscvx_nn.h $(BUILD)/libtscvx_gnc.a
	$(CC) -std=c99 -Wall -Wextra -Werror -O2 -g -Ic_runtime/include -Ic_runtime/examples $< -o $@ $(BUILD)/libtscvx_gnc.a -lm

$(BUILD)/ctest/test_nn: c_runtime/nn/tests/test_nn.c c_runtime/examples/host_io.h $(NN_HDRS) $(BUILD)/libtscvx_gnc.a
	@mkdir -p $(BUILD)/ctest
	$(CC) -std=c99 -Wall -Wextra -Werror -O1 -g -Ic_runtime/include -Ic_runtime/nn -Ic_runtime/examples $< -o $@ $(BUILD)/libtscvx_gnc.a -lm

nn-models: $(NN_MODELS)
lib: nn-models
# the card's C inference figures (guidance export) need the driver after a plain `make lib`
lib: $(BUILD)/nn_budget_driver

# The network tests again under AddressSanitizer + UBSan (part of `make ctest-asan`).
ctest-asan-nn: lib
	@mkdir -p $(BUILD)/ctest-asan
	@$(CC) -std=c99 -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined \
	  -Ic_runtime/include -Ic_runtime/nn -Ic_runtime/examples c_runtime/nn/tests/test_nn.c \
	  $(NN_SRCS) -o $(BUILD)/ctest-asan/test_nn -lm
	@echo "== test_nn (ASan/UBSan)"; $(BUILD)/ctest-asan/test_nn $(NN_MODELS)
ctest-asan: ctest-asan-nn
.PHONY: ctest-asan-nn

ctest-nn: lib $(BUILD)/ctest/test_nn $(BUILD)/nn_budget_driver
	@echo "== test_nn (valgrind)"
	@$(VALGRIND) $(BUILD)/ctest/test_nn $(NN_MODELS)
	@echo "== no heap allocation inside tscvx_nn_run (malloc interposition, native run)"
	@set -e; for m in $(NN_MODELS); do \
	  $(BUILD)/nn_budget_driver $$m > $(BUILD)/ctest/nn_budget_driver.out; \
	  grep -q '^heap_allocations_in_run 0$$' $(BUILD)/ctest/nn_budget_driver.out \
	    || { cat $(BUILD)/ctest/nn_budget_driver.out; echo "heap allocation inside tscvx_nn_run"; exit 1; }; \
	  grep -q '^status ok$$' $(BUILD)/ctest/nn_budget_driver.out \
	    || { cat $(BUILD)/ctest/nn_budget_driver.out; exit 1; }; done

.PHONY: nn-models ctest-nn
ctest: ctest-nn
