# Short forms of the project's commands. Everything also works with plain cargo.

# List the recipes.
default:
    @just --list

# Run every experiment, write the scorecard and build the book (extra ARGS go to `reproduce`).
reproduce *ARGS:
    cargo run --release --bin reproduce -- {{ARGS}}

# Run the test suite.
test:
    cargo test --release

# Run one experiment, e.g. `just fig fig08` or `just fig table3`.
fig NAME:
    cargo run --release --bin {{NAME}}

# Rebuild the book from the existing results without rerunning the experiments.
book:
    cargo run --release --bin reproduce -- --book-only

# Check formatting, lints and every crate's rustdoc (warnings are errors; the rustdoc, in the
# release profile too, reuses the dependencies clippy checked).
lint:
    cargo fmt --check
    cargo clippy --release --workspace --all-targets -- -D warnings
    RUSTDOCFLAGS="-D warnings" cargo doc --release --no-deps --workspace --lib

# Run the benchmarks.
bench:
    cargo run --release --bin bench

# Cross-check our integrator against ngspice (its numbers from the recording).
crosscheck:
    cargo run --release --bin crosscheck

# The same with ngspice run again on every netlist, checked against the recording (needs
# `apt-get install ngspice`).
crosscheck-fresh:
    cargo run --release --bin crosscheck -- --fresh-ngspice

# Run the model on your own device file, e.g. `just own sweep --device my.toml --from 500 --to 900 --accel-rms-g 0.3`.
own *ARGS:
    cargo run --release --bin endstop -- {{ARGS}}

# Why the paper deviates: Sobol indices and the multi-claim calibration (not part of `reproduce`; extra ARGS, e.g. `--base 16 --force`).
deviations *ARGS:
    cargo run --release --bin deviations -- {{ARGS}}

# Re-record the runs of `data/recorded/` (the deviations chapter's runs with the ensemble claims) with the arguments each run's `run.json` holds: hours on 2 cores; needs the Python package with Dask (`pip install "./python[examples,dask]"`). The Python tests compare a recording with the current code within its sampling error.
record:
    for d in data/recorded/*/; do python3 python/examples/study_dask.py $(python3 -c "import json, sys; print(' '.join(json.load(open(sys.argv[1]))['argv']))" "${d}run.json") || exit 1; done
