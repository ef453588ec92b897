# T-SCvx guidance: one entry point for set-up, build, tests, demo, benchmarks and models.
# `make demo` and `make test` work on a fresh Debian machine: they install what is missing.

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(VENV)/bin/pip
# The package alone builds the flight library and runs the demo and the budget (no torch);
# the tests, benchmarks and training take its extras (.[dev], about 1.7 GB with torch).
FLIGHT_STAMP := $(VENV)/.installed-flight
STAMP  := $(VENV)/.installed
# `python -m` from the checkout's root runs this checkout's package, wherever the venv's
# editable install points (several worktrees may share one venv).
GUIDANCE := $(PY) -m guidance
# gcc and python3-venv: a bare Debian image has neither a compiler nor `python3 -m venv`.
APT_PACKAGES := libeigen3-dev libsuitesparse-dev valgrind gcc python3-venv
BUILD  := build

.PHONY: all setup setup-flight apt lib gnc ctest pytest test lint analyze demo bench budget models coverage check-ppc clean

all: lib

# ---- environment -------------------------------------------------------------------------
# Installs those of the Debian packages $(1) that are missing (as root, or through sudo);
# make apt, fuzz-apt (c_runtime/fuzz/fuzz.mk) and ppc-apt (c_runtime/ppc.mk) use it.
apt_install = missing=""; for p in $(1); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi

apt:
	@$(call apt_install,$(APT_PACKAGES))

$(FLIGHT_STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -q --upgrade pip
	$(PIP) install -q -e .
	@touch $@

$(STAMP): $(FLIGHT_STAMP)
	$(PIP) install -q -e '.[dev]'
	@touch $@

setup-flight: apt $(FLIGHT_STAMP)
setup: apt $(STAMP)

# ---- flight C library (rules in c_runtime/runtime.mk) --------------------------------------
# Every flight object is compiled as the RAD750 would run it, so that callgrind's instruction
# counts stand for the flight code: scalar floating point (the PowerPC 750 has no SIMD; GCC's
# vectorizer would pack loops into SSE2 pairs and undercount), and loops kept as loops (no
# libc memset/memcpy substituted, whose x86 `rep stos` counts a byte per instruction). -O3
# rather than -O2: 3 % fewer instructions per guidance call for the same results to the last
# bit (IEEE arithmetic either way) and 28 KB more code. -funroll-loops: 7.9 % fewer again
# (2,198 M -> 2,025 M per SCvx guidance call, `make budget`), the same bits, 0.21 MiB more
# code: less loop control in the short dense loops of the KKT kernels, on the host as on a
# 2-issue PowerPC. Beyond -Wall -Wextra, the warnings a flight-code review asks for:
# shadowed names, float silently promoted to double, const cast away, functions without
# prototypes, casts that may misalign, arithmetic on void pointers, variable-length arrays,
# undefined macros in #if, format strings that are not literals.
FLIGHT_WARNINGS := -Wall -Wextra -Werror -Wshadow -Wdouble-promotion -Wcast-qual \
                   -Wstrict-prototypes -Wmissing-prototypes -Wcast-align -Wpointer-arith \
                   -Wvla -Wundef -Wformat=2
FLIGHT_CFLAGS := -std=c99 $(FLIGHT_WARNINGS) -O3 -funroll-loops -fno-tree-vectorize \
                 -fno-tree-loop-distribute-patterns
# Every flight object depends on this file, rewritten only when the flags change: a new flag
# rebuilds the library instead of leaving objects compiled with the old ones.
FLAGS_STAMP := $(BUILD)/flight_cflags
$(shell mkdir -p $(BUILD) && (echo '$(FLIGHT_CFLAGS)' | cmp -s - $(FLAGS_STAMP) || \
        echo '$(FLIGHT_CFLAGS)' > $(FLAGS_STAMP)))
# ... and written again when `make clean` removed it in the same run (`make clean lib`)
$(FLAGS_STAMP):
	@mkdir -p $(@D)
	echo '$(FLIGHT_CFLAGS)' > $@
include c_runtime/runtime.mk
include c_runtime/nn.mk
include c_runtime/guidance.mk
include c_runtime/coverage.mk
include c_runtime/ppc.mk
include c_runtime/fuzz/fuzz.mk
include c_runtime/stack.mk

# ---- tests ---------------------------------------------------------------------------------
pytest: setup lib
	$(PY) -m pytest -q

lint: setup
	$(VENV)/bin/ruff check guidance tests codegen
	$(VENV)/bin/ruff format --check guidance tests codegen
	$(VENV)/bin/mypy

# gcc's static analyzer over every hand-written flight source, its findings errors (~15 s)
analyze: lib
	@set -e; for f in $(wildcard c_runtime/src/*.c c_runtime/guidance/*.c c_runtime/nn/*.c); do \
	  $(CC) -std=c99 $(FLIGHT_WARNINGS) -O1 -fanalyzer -Ic_runtime/include -Ic_runtime/src \
	    -Ic_runtime/guidance -I$(GEN_DIR) -I/usr/include/suitesparse -c $$f -o /dev/null; done
	@echo "analyze: no findings"

test: setup lib ctest ctest-asan analyze lint pytest
# (not in `make test`: `make check-ppc`, the flight library and its C suites built for and run on
# a 32-bit big-endian PowerPC 750 under qemu, the landing compared with x86's: c_runtime/ppc.mk)

# ---- user-facing jobs ----------------------------------------------------------------------
# The default landing three ways: the ground reference, the flight library, and T-SCvx with
# the shipped networks (warm start + tight-constraint masks) in the flight library; then the
# plain C example program, without and with the networks.
demo: setup-flight lib
	@mkdir -p out
	$(GUIDANCE) solve --method scvx --backend clarabel --out out/scvx.npz --plot out/scvx.png
	$(GUIDANCE) solve --method scvx --backend c --out out/scvx_c.npz --plot out/scvx_c.png
	$(GUIDANCE) solve --method tscvx --backend c --out out/tscvx_c.npz --plot out/tscvx_c.png
	$(GUIDANCE) verify out/scvx.npz out/scvx_c.npz out/tscvx_c.npz
	./$(BUILD)/pdg_example > out/pdg_example.txt
	@grep -E '^(SCvx|status|iterations|re-plan)' out/pdg_example.txt
	./$(BUILD)/pdg_example $(BUILD)/models/solution.tnn $(BUILD)/models/constraint.tnn \
	  > out/pdg_example_tscvx.txt
	@grep -E '^(T-SCvx|status|iterations)' out/pdg_example_tscvx.txt
	@echo "the C example's whole output, trajectories included: out/pdg_example*.txt"

bench: setup lib $(BUILD)/ctest/bench_driver
	$(GUIDANCE) bench --backend clarabel c-socp c --tscvx-landings 24 --callgrind
	$(GUIDANCE) agreement --landings 20

# The default landing, then a campaign of BUDGET_LANDINGS sampled landings (about 30 s each
# under callgrind; docs/budget.md's figures are of `guidance budget --landings 20`).
BUDGET_LANDINGS ?= 4
budget: setup-flight lib
	$(GUIDANCE) budget --landings $(BUDGET_LANDINGS)

# `models` (data generation, training, export) lives with the models it makes.
-include models/models.mk

clean:
	rm -rf $(BUILD) out .pytest_cache .ruff_cache
