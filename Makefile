# visprim: every target installs what it needs into .venv first, and only when it changed.
#
# What is installed is recorded in stamp files under .venv/: the extension is rebuilt when
# the Rust sources or the dependency lists change (the Python package is installed editable,
# so a change to python/ needs no reinstall); an extra is installed again when pyproject.toml
# changes. pip's and cargo's output goes to .venv/install.log (printed if a step fails).
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
LOG    := $(VENV)/install.log
export VIRTUAL_ENV := $(abspath $(VENV))

RUST_SOURCES := Cargo.toml Cargo.lock $(shell find rust/src -name '*.rs' 2>/dev/null)
TOOLS   := $(VENV)/.stamp-tools
RUNTIME := $(VENV)/.stamp-runtime
DEV     := $(VENV)/.stamp-extra-dev
DOCS    := $(VENV)/.stamp-extra-docs

# After a command whose output went to the log: on failure, show the log's end.
ONFAIL = || { tail -n 40 $(LOG); echo "make: failed; the full log is $(LOG)"; exit 1; }

.PHONY: install demo test bench bench-against lint docs wheel wheel-check format clean

$(TOOLS):
	@echo "make: creating $(VENV) with $(PYTHON) (pip, maturin)"
	@$(PYTHON) -m venv $(VENV)
	@: > $(LOG)
	@$(PY) -m pip install --upgrade pip "maturin>=1.9.4,<2" >>$(LOG) 2>&1 $(ONFAIL)
	@touch $@

$(RUNTIME): $(TOOLS) $(RUST_SOURCES) pyproject.toml
	@echo "make: building the Rust extension (release) and installing visprim with its runtime dependencies"
	@$(VENV)/bin/maturin develop --release >>$(LOG) 2>&1 $(ONFAIL)
	@touch $@

# An extra of pyproject.toml ([project.optional-dependencies]), without rebuilding visprim.
$(VENV)/.stamp-extra-%: $(RUNTIME) pyproject.toml
	@echo "make: installing the '$*' extra"
	@$(PY) -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['$*']))" > $(VENV)/requirements-$*.txt
	@$(PY) -m pip install -r $(VENV)/requirements-$*.txt >>$(LOG) 2>&1 $(ONFAIL)
	@touch $@

install: $(DEV)  ## build the Rust extension (release), install visprim + dev tools into .venv

demo: $(RUNTIME)   ## generate the default experiment, learn primitives, write the report to out/demo
	$(VENV)/bin/visprim demo --out out/demo --force
	@echo "make: the report is out/demo/index.html (figures, tables and models in out/demo/)"

test: $(DEV)   ## cargo test + pytest, then the kernel tests at every lower SIMD level of this CPU
	cargo test --release -q
	$(PY) -m pytest -q
	for level in $$($(PY) -c 'from visprim import kernels; print(*kernels.simd_levels()[:-1])'); do \
	  echo "VISPRIM_SIMD=$$level: kernel tests"; \
	  VISPRIM_SIMD=$$level cargo test --release -q || exit 1; \
	  VISPRIM_SIMD=$$level $(PY) -m pytest -q tests/test_kernels_signal.py tests/test_kernels_signal_props.py tests/test_kernels_signal_segment.py tests/test_kernels_linalg.py tests/test_kernels_linalg_kmeans.py tests/test_kernels_determinism.py || exit 1; \
	done

bench: $(DEV)  ## criterion benches + visprim vs numpy/scipy/scikit-learn in one run
	cargo bench --bench signal --bench linalg
	$(PY) benches/compare.py

bench-against: $(DEV)  ## make bench-against REV=<commit>: that commit's kernels against these, same runs
	@test -n "$(REV)" || { echo "usage: make bench-against REV=<commit>"; exit 2; }
	$(PY) benches/against.py $(REV)

lint: $(DEV)   ## ruff, mypy (config in pyproject.toml), cargo fmt --check, clippy
	$(VENV)/bin/ruff check python tests benches docs
	$(VENV)/bin/ruff format --check python tests benches docs
	$(VENV)/bin/mypy
	cargo fmt --all -- --check
	cargo clippy --all-targets --features python -- -D warnings

docs: $(DOCS)   ## the documentation (Sphinx + numpydoc) in docs/_build/html, warnings are errors
	$(PY) -m sphinx -W -E --keep-going -q -b html docs docs/_build/html
	@echo "make: the documentation is docs/_build/html/index.html"

# The wheel: the same release profile and features as `maturin develop --release`, so cargo
# reuses that build (only packaging is new).
wheel: $(TOOLS)   ## the wheel users install, in dist/
	@echo "make: building the wheel (release) into dist/"
	@rm -f dist/visprim-*.whl
	@$(VENV)/bin/maturin build --release -i $(PY) -o dist >>$(LOG) 2>&1 $(ONFAIL)
	@ls dist/visprim-*.whl

# The wheel as users get it: a fresh virtual environment outside the source tree, used from
# a directory outside it. WHEEL_IMPORTS: the names `from visprim import ...` must give.
WHEEL_IMPORTS ?= PrimitiveModel, MotionClassifier, DTWClassifier, read
wheel-check: wheel   ## install dist/*.whl into a fresh venv outside the tree and use it there
	@PYTHON="$(PYTHON)" WHEEL_IMPORTS="$(WHEEL_IMPORTS)" .ci/wheel-check dist/visprim-*.whl

format: $(DEV)
	$(VENV)/bin/ruff format python tests benches docs
	cargo fmt --all

clean:
	rm -rf $(VENV) target out dist docs/_build
