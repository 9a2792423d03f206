# Two commands do everything on a fresh machine: `make demo` and `make test`.
# Both create the virtual environment in .venv first (idempotent: nothing happens when
# requirements.lock has not changed since the last install).

VENV      := .venv
PY        := $(VENV)/bin/python
STAMP     := $(VENV)/.installed
# Python 3.13 is required by bpy 5.2. pyenv provides it on our machines; elsewhere python3.13.
BOOT_PY   ?= $(shell if PYENV_VERSION=3.13.0 python3.13 --version >/dev/null 2>&1; \
                then echo "env PYENV_VERSION=3.13.0 python3.13"; else echo python3.13; fi)

.PHONY: setup demo test test-fast test-cpus extension bench clean

setup: $(STAMP)

$(STAMP): requirements.lock
	@test -x $(PY) || $(BOOT_PY) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.lock
	@touch $(STAMP)

demo: setup
	$(PY) -m demo_blends.run_demos --out out

test: setup
	$(PY) -m pytest -q

test-fast: setup
	$(PY) -m pytest -q -m "not slow"

# The numerically sensitive tests again as if on other CPUs (Numba, NumPy and OpenBLAS told to use
# other code paths; tools/cpu_variants.py): CI runs it after `make test`.
test-cpus: setup
	$(PY) tools/cpu_variants.py

extension: setup
	$(PY) tools/build_extension.py --out dist

# Benchmarks print figures (bench/README.md); BENCH_ARGS=--quick runs them small. Mitsuba's LLVM
# backend (Dr.Jit 1.5) needs libLLVM >= 19: Debian's libllvm19 is installed when none is found.
BENCH_ARGS ?=
bench: setup
	@ls /usr/lib/*/libLLVM* 2>/dev/null | grep -qE 'libLLVM(-|\.so\.)(19|[2-9][0-9])' \
		|| { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19; }
	$(PY) -m bench.throughput $(BENCH_ARGS)
	$(PY) -m bench.vs_mitsuba --check $(BENCH_ARGS)
	$(PY) -m bench.wavelengths $(BENCH_ARGS)

clean:
	rm -rf dist out .pytest_cache
