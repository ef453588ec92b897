# Flight C library build rules (included by the top-level Makefile).
#   make lib    -> build/libtscvx.a, build/libtscvx.so
#   make ctest  -> C unit tests under valgrind (memcheck, --error-exitcode=1), the arena-limit
#                  test (test_arena_limit) and the no-allocation-in-solve test (malloc
#                  interposition, run natively);
#                  also builds build/ctest/bench_driver (callgrind driver of guidance.bench_socp)
#   make ctest-asan -> the unit tests again under AddressSanitizer + UBSan (with the network
#                  and guidance tests: nn.mk, guidance.mk)

CRT_DIR     := c_runtime
CRT_SRCS    := $(wildcard $(CRT_DIR)/src/*.c)
CRT_HDRS    := $(wildcard $(CRT_DIR)/include/*.h) $(wildcard $(CRT_DIR)/src/*.h)
CRT_OBJDIR  := $(BUILD)/obj
CRT_OBJS    := $(patsubst $(CRT_DIR)/src/%.c,$(CRT_OBJDIR)/%.o,$(CRT_SRCS))
CRT_CC      ?= gcc
CRT_CFLAGS  := $(FLIGHT_CFLAGS) -fPIC -I$(CRT_DIR)/include -I/usr/include/suitesparse
CRT_LIBS    := -lamd -lldl -lsuitesparseconfig -lm
CRT_TESTS   := test_cones test_kkt test_solver
CRT_TESTBIN := $(addprefix $(BUILD)/ctest/,$(CRT_TESTS))
VALGRIND    := valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite

lib: apt $(BUILD)/libtscvx.a $(BUILD)/libtscvx.so

$(CRT_OBJDIR)/%.o: $(CRT_DIR)/src/%.c $(CRT_HDRS) $(FLAGS_STAMP)
	@mkdir -p $(CRT_OBJDIR)
	$(CRT_CC) $(CRT_CFLAGS) -c $< -o $@

$(BUILD)/libtscvx.a: $(CRT_OBJS)
	rm -f $@
	ar rcs $@ $(CRT_OBJS)

$(BUILD)/libtscvx.so: $(CRT_OBJS)
	$(CRT_CC) -shared -o $@ $(CRT_OBJS) $(CRT_LIBS)

$(BUILD)/ctest/%: $(CRT_DIR)/tests/%.c $(CRT_DIR)/tests/ctest_util.h $(BUILD)/libtscvx.a
	@mkdir -p $(BUILD)/ctest
	$(CRT_CC) $(CRT_CFLAGS) -g -I$(CRT_DIR)/src $< -o $@ $(BUILD)/libtscvx.a $(CRT_LIBS)

# The size queries at the arena's limit (SIZE_MAX / 2: 2 GiB with the RAD750's 32-bit size_t),
# the runtime built from the sources with a small SIZE_MAX (c_runtime/tests/small_size_t.h)
$(BUILD)/ctest/test_arena_limit: $(CRT_DIR)/tests/test_arena_limit.c $(CRT_DIR)/tests/small_size_t.h $(CRT_DIR)/tests/ctest_util.h $(CRT_SRCS) $(CRT_HDRS) $(FLAGS_STAMP)
	@mkdir -p $(BUILD)/ctest
	$(CRT_CC) $(FLIGHT_CFLAGS) -g -include $(CRT_DIR)/tests/small_size_t.h -I$(CRT_DIR)/include \
	  -I$(CRT_DIR)/src -I/usr/include/suitesparse $< $(CRT_SRCS) -o $@ $(CRT_LIBS)

ctest: lib $(CRT_TESTBIN) $(BUILD)/ctest/test_noalloc $(BUILD)/ctest/bench_driver $(BUILD)/ctest/test_arena_limit
	@set -e; for t in $(CRT_TESTS) test_arena_limit; do \
	  echo "== $$t (valgrind)"; $(VALGRIND) $(BUILD)/ctest/$$t; done
	@echo "== test_noalloc (malloc interposition)"; $(BUILD)/ctest/test_noalloc

# The same C unit tests built from the sources with AddressSanitizer + UBSan (optional).
ctest-asan: apt
	@mkdir -p $(BUILD)/ctest-asan
	@set -e; for t in $(CRT_TESTS); do \
	  $(CRT_CC) -std=c99 -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined \
	    -I$(CRT_DIR)/include -I$(CRT_DIR)/src -I/usr/include/suitesparse \
	    $(CRT_DIR)/tests/$$t.c $(CRT_SRCS) -o $(BUILD)/ctest-asan/$$t $(CRT_LIBS); \
	  echo "== $$t (ASan/UBSan)"; $(BUILD)/ctest-asan/$$t; done
	@$(CRT_CC) -std=c99 -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=undefined \
	  -include $(CRT_DIR)/tests/small_size_t.h -I$(CRT_DIR)/include -I$(CRT_DIR)/src \
	  -I/usr/include/suitesparse $(CRT_DIR)/tests/test_arena_limit.c $(CRT_SRCS) \
	  -o $(BUILD)/ctest-asan/test_arena_limit $(CRT_LIBS)
	@echo "== test_arena_limit (ASan/UBSan)"; $(BUILD)/ctest-asan/test_arena_limit

.PHONY: ctest-asan
