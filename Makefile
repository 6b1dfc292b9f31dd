# visprim: every target installs what it needs into .venv first.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
export VIRTUAL_ENV := $(abspath $(VENV))

.PHONY: install demo test bench bench-against lint docs format clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip "maturin>=1.9.4,<2"

install: $(PY)  ## build the Rust extension (release) and install visprim + dev deps into .venv
	$(VENV)/bin/maturin develop --release -q -E dev

demo: install   ## generate the default experiment, learn primitives, write the report to out/demo
	$(VENV)/bin/visprim demo --out out/demo --force

test: install   ## cargo test + pytest, then the kernel tests at every lower SIMD level of this CPU
	cargo test --release -q
	$(PY) -m pytest -q
	for level in $$($(PY) -c 'from visprim import kernels; print(*kernels.simd_levels()[:-1])'); do \
	  echo "VISPRIM_SIMD=$$level: kernel tests"; \
	  VISPRIM_SIMD=$$level cargo test --release -q || exit 1; \
	  VISPRIM_SIMD=$$level $(PY) -m pytest -q tests/test_kernels_signal.py tests/test_kernels_signal_props.py tests/test_kernels_signal_segment.py tests/test_kernels_linalg.py tests/test_kernels_linalg_kmeans.py tests/test_kernels_determinism.py || exit 1; \
	done

bench: install  ## criterion benches + visprim vs numpy/scipy/scikit-learn in one run
	cargo bench --bench signal --bench linalg
	$(PY) benches/compare.py

bench-against: install  ## make bench-against REV=<commit>: that commit's kernels against these, same runs
	@test -n "$(REV)" || { echo "usage: make bench-against REV=<commit>"; exit 2; }
	$(PY) benches/against.py $(REV)

lint: install   ## ruff, mypy (config in pyproject.toml), cargo fmt --check, clippy
	$(VENV)/bin/ruff check python tests benches
	$(VENV)/bin/ruff format --check python tests benches
	$(VENV)/bin/mypy
	cargo fmt --all -- --check
	cargo clippy --all-targets --features python -- -D warnings

docs: install   ## API reference from the docstrings (Sphinx + numpydoc), warnings are errors
	$(PY) -m sphinx -W --keep-going -q -b html docs docs/_build/html

format: $(PY)
	$(VENV)/bin/ruff format python tests benches
	cargo fmt --all

clean:
	rm -rf $(VENV) target out docs/_build
