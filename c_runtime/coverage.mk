# Structural coverage of the hand-written flight code (included by the top Makefile).
#   make coverage -> every flight source compiled with gcov instrumentation into
#                    $(COV_DIR), the C unit tests and the Python suite run against those
#                    libraries, then a table of line, branch and function coverage per file
#                    ($(COV_DIR)/coverage.txt) and the lines never run ($(COV_DIR)/uncovered.txt).
# A report, not a test: a flight review reads what the tests never reach. -O0 so that each
# line and branch of the source is one in the object; the generated model is not instrumented
# (straight-line CasADi output, checked against CasADi to 1e-12 by tests/test_codegen.py).

COV_DIR    := $(BUILD)/coverage
COV_OBJDIR := $(COV_DIR)/obj
COV_SRCS   := $(CRT_SRCS) $(GNC_SRCS) $(NN_SRCS)
COV_OBJS   := $(addprefix $(COV_OBJDIR)/,$(notdir $(COV_SRCS:.c=.o)))
COV_CRT    := $(addprefix $(COV_OBJDIR)/,$(notdir $(CRT_SRCS:.c=.o)))
COV_NN     := $(addprefix $(COV_OBJDIR)/,$(notdir $(NN_SRCS:.c=.o)))
COV_MODEL  := $(COV_DIR)/tscvx_model.o
COV_CFLAGS := -std=c99 $(FLIGHT_WARNINGS) -O0 -g --coverage -fprofile-update=atomic -fPIC \
              -Ic_runtime/include -Ic_runtime/src -Ic_runtime/guidance -I$(GEN_DIR) \
              -I/usr/include/suitesparse
COV_LIBS   := -lamd -lldl -lsuitesparseconfig -lm -lgcov
# the tests themselves are not measured: only linked with gcov's runtime
COV_TEST_CFLAGS := -std=c99 -O0 -g -Ic_runtime/include -Ic_runtime/src \
                   -Ic_runtime/guidance -Ic_runtime/nn -Ic_runtime/examples -I$(GEN_DIR)

vpath %.c c_runtime/src c_runtime/guidance c_runtime/nn

$(COV_OBJDIR)/%.o: %.c $(CRT_HDRS) $(GNC_HDRS) $(NN_HDRS) $(GEN_DIR)/tscvx_model.h $(FLAGS_STAMP)
	@mkdir -p $(COV_OBJDIR)
	$(CC) $(COV_CFLAGS) -c $< -o $@

$(COV_MODEL): $(GEN_DIR)/tscvx_model.c
	@mkdir -p $(COV_DIR)
	$(CC) -std=c99 -O1 -fPIC -c $< -o $@

$(COV_DIR)/libtscvx.so: $(COV_CRT)
	$(CC) -shared --coverage -o $@ $^ $(COV_LIBS)

$(COV_DIR)/libtscvx_gnc.so: $(COV_OBJS) $(COV_MODEL)
	$(CC) -shared --coverage -o $@ $^ $(COV_LIBS)

# The C unit tests, each linked with the instrumented objects it needs.
$(COV_DIR)/test_%: c_runtime/tests/test_%.c $(COV_CRT)
	$(CC) $(COV_TEST_CFLAGS) $< -o $@ $(COV_CRT) $(COV_LIBS)
$(COV_DIR)/test_nn: c_runtime/nn/tests/test_nn.c $(COV_NN)
	$(CC) $(COV_TEST_CFLAGS) $< -o $@ $(COV_NN) -lm -lgcov
$(COV_DIR)/test_guidance $(COV_DIR)/test_tscvx: $(COV_DIR)/%: c_runtime/guidance/tests/%.c $(COV_OBJS) $(COV_MODEL)
	$(CC) $(COV_TEST_CFLAGS) $< -o $@ $(COV_OBJS) $(COV_MODEL) $(COV_LIBS)

COV_TESTBIN := $(addprefix $(COV_DIR)/,$(CRT_TESTS) test_nn $(GNC_TESTS))

# Counts start from zero at every run; a failing test is reported and the table still printed
# (coverage of a failing suite is still worth reading), and make then fails.
coverage: setup lib $(COV_DIR)/libtscvx.so $(COV_DIR)/libtscvx_gnc.so $(COV_TESTBIN)
	@find $(COV_DIR) -name '*.gcda' -delete
	@failed=0; for t in $(CRT_TESTS) $(GNC_TESTS); do \
	  echo "== $$t (instrumented)"; $(COV_DIR)/$$t > $(COV_DIR)/$$t.log 2>&1 \
	    || { echo "$$t failed: $(COV_DIR)/$$t.log"; failed=1; }; done; \
	echo "== test_nn (instrumented)"; $(COV_DIR)/test_nn $(NN_MODELS) > $(COV_DIR)/test_nn.log 2>&1 \
	  || { echo "test_nn failed: $(COV_DIR)/test_nn.log"; failed=1; }; \
	echo "== pytest against the instrumented libraries"; \
	TSCVX_LIB=$(abspath $(COV_DIR)/libtscvx.so) TSCVX_GNC_LIB=$(abspath $(COV_DIR)/libtscvx_gnc.so) \
	  $(PY) -m pytest -q -p no:cacheprovider > $(COV_DIR)/pytest.log 2>&1 \
	  || { tail -5 $(COV_DIR)/pytest.log; echo "pytest failed: $(COV_DIR)/pytest.log"; failed=1; }; \
	$(PY) -m guidance.ccoverage $(COV_OBJDIR) --out $(COV_DIR) && exit $$failed

.PHONY: coverage
