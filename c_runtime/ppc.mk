# The flight library on the RAD750's kind of CPU: 32-bit big-endian PowerPC (included by the
# top Makefile; not part of `make test`).
#   make check-ppc -> installs Debian's cross compiler and qemu-user if missing (like `apt`),
#                     cross-builds SuiteSparse's AMD, LDL and SuiteSparse_config from Debian's
#                     own source package (the x86 host's version; only those sources, nothing
#                     committed), the flight library with FLIGHT_CFLAGS for a PowerPC 750, the
#                     C test suites, the budget drivers and the example into $(PPC_DIR); runs
#                     them under qemu-ppc -cpu 750 with the x86 build's generated model and
#                     network files (written little-endian on x86: the weights are copied and
#                     byte-swapped); and compares the default landing (SCvx and T-SCvx) and
#                     the networks' outputs with the x86 build's, bit for bit (the drivers'
#                     solution_fnv1a, a digest of x and u independent of the byte order, and
#                     output_sum). 31 to 47 min here, 28 Nov (README: the figures).
# qemu 7.2 takes the ISA 3.0 forms of mffs that Debian's powerpc glibc uses in a few libm
# functions (a 750 reads them as mffs) for illegal instructions: the programs run with
# c_runtime/tests/qemu_ppc_mffs.c preloaded, which gives them the 750's meaning.

PPC_DIR      := $(BUILD)/ppc
PPC_CC       := powerpc-linux-gnu-gcc
PPC_AR       := powerpc-linux-gnu-ar
PPC_SYSROOT  := /usr/powerpc-linux-gnu
PPC_QEMU     := qemu-ppc -L $(PPC_SYSROOT) -cpu 750
PPC_PACKAGES := gcc-powerpc-linux-gnu qemu-user
# -mcpu=750: the RAD750's core (scalar FPU with fmadd, no AltiVec); -std=c99 keeps FP
# contraction off (-ffp-contract=off), so fmadd is never substituted for a*b+c.
PPC_CFLAGS   := $(FLIGHT_CFLAGS) -mcpu=750
PPC_SS       := $(PPC_DIR)/suitesparse
PPC_SSLIBS   := $(PPC_SS)/lib/libamd.a $(PPC_SS)/lib/libldl.a $(PPC_SS)/lib/libsuitesparseconfig.a
PPC_SS_INC   := -I$(PPC_SS)/include
PPC_LINK     := -L$(PPC_SS)/lib -lamd -lldl -lsuitesparseconfig -lm
PPC_OBJ      := $(PPC_DIR)/obj

# ---- tools and sources from Debian ---------------------------------------------------------
# Idempotent: packages only when missing; a deb-src entry for Debian's own mirror only when
# apt knows no source of suitesparse (the host's suite, from /etc/os-release, on the mirror its
# apt sources already name).
PPC_SRC_LIST := /etc/apt/sources.list.d/tscvx-debian-src.sources
ppc-apt: apt
	@SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	if ! apt-cache showsrc suitesparse 2>/dev/null | grep -q '^Package: suitesparse'; then \
	  . /etc/os-release; \
	  uri=$$(sed -n 's/^URIs: *//p' /etc/apt/sources.list.d/debian.sources 2>/dev/null | head -n 1); \
	  [ -n "$$uri" ] || uri=$$(awk '$$1 == "deb" { print $$2; exit }' /etc/apt/sources.list 2>/dev/null); \
	  [ -n "$$uri" ] || { echo "ppc-apt: no Debian mirror in the apt sources to take deb-src from"; exit 1; }; \
	  echo "enabling Debian's deb-src ($$VERSION_CODENAME, the mirror of the apt sources): $(PPC_SRC_LIST)"; \
	  printf 'Types: deb-src\nURIs: %s\nSuites: %s\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
	    "$$uri" "$$VERSION_CODENAME" | $$SUDO tee $(PPC_SRC_LIST) >/dev/null; \
	  $$SUDO apt-get update -qq; fi
	@$(call apt_install,$(PPC_PACKAGES))

# Debian's source package of the SuiteSparse the x86 build links (same version, checked
# against Debian's signed index by apt), unpacked to the three libraries' C sources only.
$(PPC_SS)/.unpacked: | ppc-apt
	@rm -rf $(PPC_SS) && mkdir -p $(PPC_SS)/dl $(PPC_SS)/include $(PPC_SS)/lib
	@v=$$(dpkg-query -W -f='$${source:Version}' libsuitesparse-dev); \
	echo "fetching Debian's source package suitesparse $$v (AMD, LDL, SuiteSparse_config only)"; \
	cd $(PPC_SS)/dl && apt-get source -qq --download-only "suitesparse=$$v" 2>&1 \
	  | grep -v 'unsandboxed' || true
	@tar -xJf $(PPC_SS)/dl/suitesparse_*.orig.tar.xz -C $(PPC_SS) --strip-components=1 \
	  --wildcards '*/AMD/Source/amd_*.c' '*/AMD/Include/*.h' '*/LDL/Source/ldl.c' \
	  '*/LDL/Include/ldl.h' '*/SuiteSparse_config/SuiteSparse_config.[ch]'
	@rm -rf $(PPC_SS)/dl
	@cp $(PPC_SS)/AMD/Include/*.h $(PPC_SS)/LDL/Include/ldl.h \
	  $(PPC_SS)/SuiteSparse_config/SuiteSparse_config.h $(PPC_SS)/include/
	@touch $@

# The int versions only (the runtime calls amd_2, amd_defaults, ldl_*), as Debian's
# AMD/Lib and LDL/Lib makefiles compile them (-DDINT), FP contraction off as on x86-64.
PPC_SS_CFLAGS := -O3 -mcpu=750 -ffp-contract=off -I$(PPC_SS)/include
PPC_AMD := aat 1 2 dump postorder defaults post_tree order control info valid preprocess
$(PPC_SSLIBS) &: $(PPC_SS)/.unpacked
	@mkdir -p $(PPC_SS)/obj
	@set -e; for f in $(PPC_AMD); do \
	  $(PPC_CC) $(PPC_SS_CFLAGS) -DDINT -c $(PPC_SS)/AMD/Source/amd_$$f.c -o $(PPC_SS)/obj/amd_i_$$f.o; done
	$(PPC_CC) $(PPC_SS_CFLAGS) -c $(PPC_SS)/LDL/Source/ldl.c -o $(PPC_SS)/obj/ldl.o
	$(PPC_CC) $(PPC_SS_CFLAGS) -c $(PPC_SS)/SuiteSparse_config/SuiteSparse_config.c \
	  -o $(PPC_SS)/obj/SuiteSparse_config.o
	rm -f $(PPC_SSLIBS)
	$(PPC_AR) rcs $(PPC_SS)/lib/libamd.a $(PPC_SS)/obj/amd_i_*.o
	$(PPC_AR) rcs $(PPC_SS)/lib/libldl.a $(PPC_SS)/obj/ldl.o
	$(PPC_AR) rcs $(PPC_SS)/lib/libsuitesparseconfig.a $(PPC_SS)/obj/SuiteSparse_config.o

# ---- the flight library, tests and programs ---------------------------------------------------
PPC_CRT_OBJS := $(patsubst $(CRT_DIR)/src/%.c,$(PPC_OBJ)/crt/%.o,$(CRT_SRCS))
PPC_NN_OBJS  := $(patsubst c_runtime/nn/%.c,$(PPC_OBJ)/nn/%.o,$(NN_SRCS))
PPC_GNC_OBJS := $(patsubst c_runtime/guidance/%.c,$(PPC_OBJ)/gnc/%.o,$(GNC_SRCS)) \
                $(PPC_OBJ)/gnc/tscvx_model.o $(PPC_NN_OBJS)

$(PPC_OBJ)/crt/%.o: $(CRT_DIR)/src/%.c $(CRT_HDRS) $(FLAGS_STAMP) $(PPC_SSLIBS)
	@mkdir -p $(@D)
	$(PPC_CC) $(PPC_CFLAGS) -I$(CRT_DIR)/include $(PPC_SS_INC) -c $< -o $@
$(PPC_OBJ)/nn/%.o: c_runtime/nn/%.c $(NN_HDRS) $(FLAGS_STAMP) | ppc-apt
	@mkdir -p $(@D)
	$(PPC_CC) $(PPC_CFLAGS) -Ic_runtime/include -c $< -o $@
$(PPC_OBJ)/gnc/tscvx_model.o: $(GEN_DIR)/tscvx_model.c $(FLAGS_STAMP) | ppc-apt
	@mkdir -p $(@D)
	$(PPC_CC) $(PPC_CFLAGS) -I$(GEN_DIR) -Wno-unused-parameter -Wno-missing-prototypes -c $< -o $@
$(PPC_OBJ)/gnc/%.o: c_runtime/guidance/%.c $(GNC_HDRS) $(GEN_DIR)/tscvx_model.h $(FLAGS_STAMP) | ppc-apt
	@mkdir -p $(@D)
	$(PPC_CC) $(PPC_CFLAGS) -Ic_runtime/include -Ic_runtime/guidance -I$(GEN_DIR) -c $< -o $@

$(PPC_DIR)/libtscvx.a: $(PPC_CRT_OBJS)
	rm -f $@ && $(PPC_AR) rcs $@ $^
$(PPC_DIR)/libtscvx_gnc.a: $(PPC_GNC_OBJS)
	rm -f $@ && $(PPC_AR) rcs $@ $^

PPC_LIBS := $(PPC_DIR)/libtscvx_gnc.a $(PPC_DIR)/libtscvx.a
# the test programs with the flags their x86 rules use (runtime.mk, nn.mk, guidance.mk)
PPC_TEST_INC := -Ic_runtime/include -Ic_runtime/src -Ic_runtime/guidance -Ic_runtime/nn \
                -Ic_runtime/examples -I$(GEN_DIR) $(PPC_SS_INC)
$(PPC_DIR)/test_%: $(CRT_DIR)/tests/test_%.c $(CRT_DIR)/tests/ctest_util.h $(PPC_DIR)/libtscvx.a
	$(PPC_CC) $(PPC_CFLAGS) -g $(PPC_TEST_INC) $< -o $@ $(PPC_DIR)/libtscvx.a $(PPC_LINK)
$(PPC_DIR)/test_nn: c_runtime/nn/tests/test_nn.c c_runtime/examples/host_io.h $(NN_HDRS) $(PPC_DIR)/libtscvx_gnc.a
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O1 -g -mcpu=750 $(PPC_TEST_INC) $< -o $@ $(PPC_DIR)/libtscvx_gnc.a -lm
$(PPC_DIR)/test_guidance $(PPC_DIR)/test_tscvx: $(PPC_DIR)/%: c_runtime/guidance/tests/%.c c_runtime/guidance/tests/gnc_test.h c_runtime/include/tscvx_guidance.h c_runtime/examples/host_io.h $(PPC_LIBS)
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O1 -g -mcpu=750 $(PPC_TEST_INC) $< -o $@ $(PPC_LIBS) $(PPC_LINK)
$(PPC_DIR)/pdg_example $(PPC_DIR)/pdg_budget_driver: $(PPC_DIR)/%: c_runtime/examples/%.c c_runtime/examples/host_io.h c_runtime/examples/measure.h c_runtime/include/tscvx_guidance.h c_runtime/include/tscvx_nn.h $(PPC_LIBS)
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O2 -g -mcpu=750 -Ic_runtime/include $< -o $@ $(PPC_LIBS) $(PPC_LINK)
$(PPC_DIR)/nn_budget_driver: c_runtime/nn/tests/nn_budget_driver.c c_runtime/examples/measure.h c_runtime/examples/host_io.h c_runtime/include/tscvx_nn.h $(PPC_DIR)/libtscvx_gnc.a
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O2 -g -mcpu=750 -Ic_runtime/include -Ic_runtime/examples $< -o $@ $(PPC_DIR)/libtscvx_gnc.a -lm

# host tooling for qemu (c_runtime/tests/qemu_ppc_mffs.c): glibc's ISA 3.0 mffs forms as a 750
$(PPC_DIR)/qemu_ppc_mffs.so: c_runtime/tests/qemu_ppc_mffs.c | ppc-apt
	@mkdir -p $(@D)
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O2 -fPIC -shared $< -o $@
$(PPC_DIR)/test_arena_limit: $(CRT_DIR)/tests/test_arena_limit.c $(CRT_DIR)/tests/small_size_t.h $(CRT_DIR)/tests/ctest_util.h $(CRT_SRCS) $(CRT_HDRS) $(PPC_SSLIBS)
	$(PPC_CC) $(PPC_CFLAGS) -g -include $(CRT_DIR)/tests/small_size_t.h -I$(CRT_DIR)/include \
	  -I$(CRT_DIR)/src $(PPC_SS_INC) $< $(CRT_SRCS) -o $@ $(PPC_LINK)
$(PPC_DIR)/test_libm_hypot: c_runtime/guidance/tests/test_libm_hypot.c c_runtime/guidance/tests/gnc_test.h c_runtime/include/tscvx_guidance.h $(PPC_LIBS)
	$(PPC_CC) -std=c99 -Wall -Wextra -Werror -O1 -g -mcpu=750 -Ic_runtime/include $< -o $@ \
	  -Wl,--wrap=hypot $(PPC_LIBS) $(PPC_LINK)

PPC_PROGS := $(addprefix $(PPC_DIR)/,$(CRT_TESTS) test_noalloc test_arena_limit test_nn \
               $(GNC_TESTS) test_libm_hypot pdg_example pdg_budget_driver nn_budget_driver \
               qemu_ppc_mffs.so)
ppc-build: $(PPC_PROGS)

# ---- run and compare --------------------------------------------------------------------------
PPC_RUN  := $(PPC_QEMU) -E LD_PRELOAD=$(abspath $(PPC_DIR)/qemu_ppc_mffs.so)
PPC_LAND := status iterations subproblems socp_iterations m_f solution_fnv1a
PPC_TSCVX_ARGS := --tscvx $(BUILD)/models/solution.tnn --masks $(BUILD)/models/constraint.tnn
check-ppc: lib ppc-build $(BUILD)/pdg_budget_driver
	@echo "== $(PPC_CC) -mcpu=750, run by qemu-ppc -cpu 750 ($$(qemu-ppc -version | head -1))"
	@set -e; for t in $(CRT_TESTS) test_noalloc test_arena_limit $(GNC_TESTS) test_libm_hypot; do \
	  echo "== $$t (qemu-ppc)"; s=$$(date +%s); \
	  $(PPC_RUN) $(PPC_DIR)/$$t > $(PPC_DIR)/$$t.out 2>&1 \
	    || { tail -20 $(PPC_DIR)/$$t.out; echo "$$t failed on ppc"; exit 1; }; \
	  echo "   $$(tail -1 $(PPC_DIR)/$$t.out) ($$(( $$(date +%s) - s )) s)"; done
	@echo "== test_nn (qemu-ppc; the x86 build's little-endian network files, weights byte-swapped)"
	@$(PPC_RUN) $(PPC_DIR)/test_nn $(NN_MODELS) > $(PPC_DIR)/test_nn.out 2>&1 \
	  || { tail -20 $(PPC_DIR)/test_nn.out; echo "test_nn failed on ppc"; exit 1; }
	@grep -E '^(build|test_nn)' $(PPC_DIR)/test_nn.out
	@echo "== the networks' outputs: ppc against x86, to the bit (nn_budget_driver's output_sum)"
	@set -e; for m in $(NN_MODELS); do \
	  x=$$(./$(BUILD)/nn_budget_driver $$m | grep -E '^(status|heap_allocations_in_run|output_sum) '); \
	  p=$$($(PPC_RUN) $(PPC_DIR)/nn_budget_driver $$m | grep -E '^(status|heap_allocations_in_run|output_sum) '); \
	  echo "   $$m: ppc $$(echo $$p | tr '\n' ' ')"; \
	  [ "$$x" = "$$p" ] || { echo "x86: $$x"; echo "$$m: ppc and x86 differ"; exit 1; }; done
	@echo "== the default landing: ppc against x86, to the bit"
	@set -e; for mode in "" "$(PPC_TSCVX_ARGS)"; do \
	  ./$(BUILD)/pdg_budget_driver $$mode > $(PPC_DIR)/landing_x86.out || true; \
	  $(PPC_RUN) $(PPC_DIR)/pdg_budget_driver $$mode > $(PPC_DIR)/landing_ppc.out || true; \
	  grep -q '^heap_allocations_in_solve 0$$' $(PPC_DIR)/landing_ppc.out \
	    || { cat $(PPC_DIR)/landing_ppc.out; echo "allocation inside the solve on ppc"; exit 1; }; \
	  for k in $(PPC_LAND); do grep "^$$k " $(PPC_DIR)/landing_x86.out; done > $(PPC_DIR)/landing_x86.key; \
	  for k in $(PPC_LAND); do grep "^$$k " $(PPC_DIR)/landing_ppc.out; done > $(PPC_DIR)/landing_ppc.key; \
	  echo "-- $$(grep '^mode ' $(PPC_DIR)/landing_ppc.out): ppc $$(tr '\n' ' ' < $(PPC_DIR)/landing_ppc.key)"; \
	  grep -q '^status solved$$' $(PPC_DIR)/landing_ppc.key \
	    || { echo "the default landing is not solved on ppc"; exit 1; }; \
	  diff $(PPC_DIR)/landing_x86.key $(PPC_DIR)/landing_ppc.key \
	    || { echo "ppc and x86 landings differ"; exit 1; }; done
	@echo "== pdg_example (qemu-ppc): SCvx with a re-plan, then T-SCvx with both networks"
	@$(PPC_RUN) $(PPC_DIR)/pdg_example > $(PPC_DIR)/pdg_example.txt
	@$(PPC_RUN) $(PPC_DIR)/pdg_example $(BUILD)/models/solution.tnn $(BUILD)/models/constraint.tnn \
	  > $(PPC_DIR)/pdg_example_tscvx.txt
	@grep -h -E '^(status|iterations|re-plan)' $(PPC_DIR)/pdg_example.txt $(PPC_DIR)/pdg_example_tscvx.txt
	@echo "check-ppc: every C suite passed on ppc; the landings and network outputs match x86 to the bit"

.PHONY: ppc-apt ppc-build check-ppc
