# Fuzzing of the flight library's input surfaces (included by the top Makefile).
#   make fuzz             libFuzzer + ASan/UBSan (clang), each harness FUZZ_SECONDS (default
#                         1200) in turn, one process, one core; installs clang and libFuzzer
#                         (Debian's clang-14) when missing. Not part of `make test`.
#   make ctest-asan-fuzz  every harness built with gcc and ASan/UBSan around fuzz_replay.c,
#                         run over its checked-in corpus c_runtime/fuzz/corpus/<harness>/
#                         (part of `make ctest-asan`: the inputs the fuzzer found stay
#                         guarded without clang).
# Harnesses (c_runtime/fuzz/fuzz_<name>.c, each documents its input and oracle):
#   nn        network blobs: check / arena size / init in place and copied, inference
#   socp      the SOCP runtime: data, settings, setup, solve, update, warm start, solve;
#             a SOLVED answer checked against the raw data
#   guidance  a small landing with mutated settings, vehicle, scenario, guess and masks;
#             a SOLVED trajectory checked against its boundary conditions and constraints
# Working corpora, crash artifacts and logs: build/fuzz/<harness>/. A crash stops the run
# (make fails) with the input in build/fuzz/<harness>/artifacts/: minimize it
# (build/fuzz/fuzz_<harness> -minimize_crash=1 -runs=10000 FILE), fix, and check the
# minimized input into c_runtime/fuzz/corpus/<harness>/.

FUZZ_SECONDS  ?= 1200
FUZZ_HARNESS  := nn socp guidance
FUZZ_CLANG    := clang-14
FUZZ_APT      := clang-14 libclang-rt-14-dev libfuzzer-14-dev
FUZZ_DIR      := $(BUILD)/fuzz
FUZZ_INC      := -Ic_runtime/include -Ic_runtime/fuzz -Ic_runtime/guidance -I$(GEN_DIR) \
                 -I/usr/include/suitesparse
FUZZ_SAN      := -g -O1 -fsanitize=address,undefined -fno-sanitize-recover=all
FUZZ_LIBS     := -lamd -lldl -lsuitesparseconfig -lm
FUZZ_SRCS_nn       := $(NN_SRCS)
FUZZ_SRCS_socp     := $(CRT_SRCS)
FUZZ_SRCS_guidance := $(GNC_SRCS) $(GEN_DIR)/tscvx_model.c $(NN_SRCS) $(CRT_SRCS)
FUZZ_DEPS     := c_runtime/fuzz/fuzz.h $(CRT_HDRS) $(NN_HDRS) $(GNC_HDRS) $(CRT_SRCS) $(NN_SRCS) \
                 $(GNC_SRCS)

fuzz-apt:
	@$(call apt_install,$(FUZZ_APT))

# clang: the harness with -Wall -Wextra -Werror, the library sources without -Werror. The
# flight warnings are gcc's (replay_% below builds the harnesses with them): clang's
# -Wdouble-promotion also flags double -> long double (the SOCP oracle's sums) and NAN /
# INFINITY, float constants, in the library.
$(FUZZ_DIR)/fuzz_%: c_runtime/fuzz/fuzz_%.c $(FUZZ_DEPS) $(GEN_DIR)/tscvx_model.c | fuzz-apt
	@mkdir -p $(FUZZ_DIR)
	$(FUZZ_CLANG) -std=c99 -Wall -Wextra -Werror $(FUZZ_SAN) -fsanitize=fuzzer $(FUZZ_INC) \
	  -c $< -o $@.o
	$(FUZZ_CLANG) -std=c99 $(FUZZ_SAN) -fsanitize=fuzzer $(FUZZ_INC) $@.o \
	  $(FUZZ_SRCS_$*) -o $@ $(FUZZ_LIBS)

# gcc, the harness with the flight warnings, around the replay driver
$(FUZZ_DIR)/replay_%: c_runtime/fuzz/fuzz_%.c c_runtime/fuzz/fuzz_replay.c $(FUZZ_DEPS) $(GEN_DIR)/tscvx_model.c
	@mkdir -p $(FUZZ_DIR)
	$(CC) -std=c99 $(FLIGHT_WARNINGS) $(FUZZ_SAN) $(FUZZ_INC) -c $< -o $@.o
	$(CC) -std=c99 $(FLIGHT_WARNINGS) $(FUZZ_SAN) $(FUZZ_INC) -c c_runtime/fuzz/fuzz_replay.c \
	  -o $@.main.o
	$(CC) -std=c99 -g -O1 -fno-var-tracking-assignments -fsanitize=address,undefined \
	  -fno-sanitize-recover=all $(FUZZ_INC) $@.o $@.main.o $(FUZZ_SRCS_$*) -o $@ $(FUZZ_LIBS)

ctest-asan-fuzz: lib $(addprefix $(FUZZ_DIR)/replay_,$(FUZZ_HARNESS))
	@set -e; for h in $(FUZZ_HARNESS); do \
	  echo "== fuzz corpus $$h (replay, ASan/UBSan)"; \
	  $(FUZZ_DIR)/replay_$$h c_runtime/fuzz/corpus/$$h/*; done
ctest-asan: ctest-asan-fuzz

# Seeds: the checked-in corpus; for the networks also the shipped ones (run once each: at
# 10 MB they are too large to mutate quickly) and tiny generated ones (nn_seeds.py).
fuzz: fuzz-apt lib $(addprefix $(FUZZ_DIR)/fuzz_,$(FUZZ_HARNESS))
	@set -e; for h in $(FUZZ_HARNESS); do \
	  mkdir -p $(FUZZ_DIR)/$$h/corpus $(FUZZ_DIR)/$$h/artifacts; \
	  cp c_runtime/fuzz/corpus/$$h/* $(FUZZ_DIR)/$$h/corpus/; done
	$(PY) c_runtime/fuzz/nn_seeds.py $(FUZZ_DIR)/nn/corpus
	$(FUZZ_DIR)/fuzz_nn $(NN_MODELS)
	@set -e; for h in $(FUZZ_HARNESS); do \
	  echo "== fuzz $$h ($(FUZZ_SECONDS) s; log $(FUZZ_DIR)/$$h/fuzz.log)"; \
	  $(FUZZ_DIR)/fuzz_$$h -max_total_time=$(FUZZ_SECONDS) -max_len=8192 -timeout=60 \
	    -print_final_stats=1 -artifact_prefix=$(FUZZ_DIR)/$$h/artifacts/ \
	    $(FUZZ_DIR)/$$h/corpus > $(FUZZ_DIR)/$$h/fuzz.log 2>&1 \
	    || { tail -40 $(FUZZ_DIR)/$$h/fuzz.log; exit 1; }; \
	  grep '^stat::number_of_executed_units\|^stat::new_units' $(FUZZ_DIR)/$$h/fuzz.log; done

.PHONY: fuzz fuzz-apt ctest-asan-fuzz
