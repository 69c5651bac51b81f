# egt: every task a person or CI runs, in one place. `make help` lists them.
# Each target does its own set-up: cargo fetches crates, Python work happens
# in a local virtualenv (.venv) built here, never in the system Python.

PYTHON ?= python3
VENV   ?= .venv
VPY    := $(VENV)/bin/python
EXAMPLE ?= examples/fig3_example61.toml

.PHONY: help demo test test-rust test-release test-python venv python-dev wheel test-wheel fmt lint bench chart clean

help: ## List the targets
	@grep -E '^[a-zA-Z_-]+:.*?## ' $(MAKEFILE_LIST) | awk -F':.*?## ' '{printf "  %-12s %s\n", $$1, $$2}'

# A debug build: the quickest to compile, instant on the example, and the
# build `make test` reuses (`cargo build --release` for a fast binary).
demo: ## Run egt on a bundled example: topology checks, circuit table, speeds
	cargo run --quiet -p egt-cli -- check $(EXAMPLE)
	cargo run --quiet -p egt-cli -- kinematics $(EXAMPLE)

test: test-rust test-python ## Run every test (Rust and Python)

# The jit runs select the whole workspace (--workspace --features
# egt-core/jit), not `-p egt-core`: the dependencies then keep the features
# the workspace's other crates give them, and only egt's own crates
# recompile (`-p egt-core` rebuilt about 30 dependencies: 98 s against 66 s).
test-rust: ## Rust unit, integration, CLI and doc tests (a default build), and the unit tests with the opt-in jit feature (compiled programs against the interpreter)
	cargo fetch --locked || cargo fetch
	cargo test --workspace --all-targets
	cargo test --workspace --doc
	cargo test --workspace --lib --features egt-core/jit

# Not in CI (it compiles the core's dependency tree once more, optimised:
# about 15 minutes on 2 cores): the core's tests optimised, with the opt-in
# jit feature. Run it after touching the batch executors.
test-release: ## The core's tests optimised (straight-line and compiled programs) with the opt-in jit feature
	cargo test --release -p egt-core --features jit --lib --test core

$(VENV)/.ready: crates/egt-py/requirements-dev.txt
	$(PYTHON) -m venv $(VENV)
	$(VPY) -m pip install --quiet --upgrade pip
	$(VPY) -m pip install --quiet -r crates/egt-py/requirements-dev.txt
	touch $@

venv: $(VENV)/.ready ## Create the Python virtualenv with the test tools

python-dev: venv ## Build and install the egt Python module into the virtualenv
	@if [ -f crates/egt-py/pyproject.toml ]; then \
		VIRTUAL_ENV=$(abspath $(VENV)) PATH=$(abspath $(VENV))/bin:$$PATH \
		$(VENV)/bin/maturin develop --release --quiet -m crates/egt-py/Cargo.toml; \
	fi

# The wheel carries egt-fmu's shared library (`Train.export_fmu`, the wheel's
# `egt fmu`; docs/fmu.md). egt-py depends on egt-fmu, so maturin's own cargo
# build also writes egt-fmu's cdylib to deps/, linked by the same zig for
# glibc 2.17 and stripped (the release profile): no second build. The
# package gets a symbolic link to it before maturin runs, which resolves
# once cargo has built it and which pyproject.toml's `include` packs.
WHEEL_DEPS := $(abspath $(or $(CARGO_TARGET_DIR),target))/x86_64-unknown-linux-gnu/release/deps
wheel: venv ## Build the abi3 manylinux2014 wheel (stripped, with the licences, the egt command and egt-fmu's library) into target/wheels; zig (from PyPI) links it
	ln -sfn $(WHEEL_DEPS)/libegt_fmu.so crates/egt-py/python/egt/libegt_fmu.so
	PATH=$(abspath $(VENV))/bin:$$PATH $(VENV)/bin/maturin build --release --zig --compatibility manylinux2014 --strip -m crates/egt-py/Cargo.toml -o target/wheels

test-wheel: wheel ## Install the wheel into a fresh virtualenv with no Rust on PATH; run the egt command and the README's Python block
	bash scripts/test_wheel.sh

# The tests run against the wheel `make wheel` builds (installed into .venv),
# so CI's wheel job and the tests share one release build.
test-python: wheel ## Python tests against the built wheel (pytest, warnings as errors; stubtest and mypy included)
	$(VPY) -m pip install --quiet --force-reinstall --no-deps "$$(ls -t target/wheels/egt_gears-*-cp39-abi3-manylinux2014_x86_64*.whl | head -n 1)"
	$(VPY) -m pytest -q -W error crates/egt-py/tests

fmt: ## Format the Rust code
	cargo fmt --all

lint: ## Clippy (the workspace, without and with egt-core's opt-in jit feature), format check, the core's docs (no broken links, no missing docs) and the minimum Rust version
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings
	cargo clippy --workspace --all-targets --features egt-core/jit -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc -p egt-core --no-deps
	python3 scripts/msrv.py
	python3 scripts/layers.py

bench: ## Benchmarks by phase and train size, 3 to 30 links (divan, short settings; see docs/performance.md)
	cargo bench -p egt-core --features jit --bench scenarios -- --sample-count 20 --min-time 0.05

chart: venv ## Re-measure Rust, SymPy and NumPy side by side; redraw docs/img/speed_accuracy.svg and the docs' tables
	cargo run --release --quiet -p egt-core --features jit --example speed_accuracy -- target/speed_accuracy
	EGT_JIT=0 cargo run --release --quiet -p egt-core --features jit --example speed_accuracy -- target/speed_accuracy/interpreted
	$(VPY) bench/routes.py target/speed_accuracy
	$(VPY) bench/chart.py target/speed_accuracy docs/img/speed_accuracy.svg docs/performance.md docs/accuracy.md

clean: ## Remove build outputs and the virtualenv
	cargo clean
	rm -rf $(VENV)

FUZZ_SECONDS ?= 30
FUZZ_TARGETS := spec adjacency input_value program search_spec batch_args shift_sim_args

.PHONY: fuzz-seed fuzz-build fuzz-smoke
fuzz-seed: ## Seed fuzz/corpus/* from examples/ (specs, adjacency strings, input values) and a few trains for the program target
	bash fuzz/seed-corpus.sh

# The CI run: coverage-guided libFuzzer on the pinned stable toolchain
# (RUSTC_BOOTSTRAP for cargo-fuzz's flags), no sanitizer: egt-core's one
# unsafe block runs the compiled batch program (the spec target reaches it),
# and what is looked for is panics, aborts, timeouts and memory.
# CI builds the harnesses unoptimised (FUZZ_BUILD=--dev): 2.3 minutes against
# 9 for -O on 2 cores, with overflow checks and debug assertions on; about 20
# times fewer runs a second. Long runs use FUZZ_BUILD=-O (docs/fuzzing.md).
FUZZ_SANITIZER ?= none
FUZZ_BUILD ?= --dev
fuzz-build: ## Build every fuzz harness (FUZZ_BUILD, FUZZ_SANITIZER; installs cargo-fuzz), which `fuzz-smoke` then runs without building
	@command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
	cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz build --sanitizer $(FUZZ_SANITIZER) $(FUZZ_BUILD)

fuzz-smoke: fuzz-seed fuzz-build ## A short libFuzzer run of every fuzz target (FUZZ_SECONDS each; see docs/fuzzing.md)
	cd fuzz && for t in $(FUZZ_TARGETS); do \
		RUSTC_BOOTSTRAP=1 cargo fuzz run --sanitizer $(FUZZ_SANITIZER) $(FUZZ_BUILD) $$t corpus/$$t -- -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 > $$t.log 2>&1 \
			|| { tail -n 60 $$t.log; echo "fuzz target $$t failed: full log fuzz/$$t.log, crash in fuzz/artifacts/$$t/"; exit 1; }; \
		grep -E '^Done [0-9]+ runs' $$t.log | sed "s/^/$$t: /"; \
	done
