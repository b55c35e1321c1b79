"""Shared fixtures: the repository root, and the Rust command-line programs run on the same
device and seed as the Python calls (through `cargo run --release`, which reuses the workspace's
release build)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def run_cli(args, out_dir, program="endstop"):
    """Runs a workspace binary with results under `out_dir`; returns its summary.json."""
    env = dict(os.environ, ENDSTOP_OUTPUT_DIR=str(out_dir))
    cmd = ["cargo", "run", "--release", "--quiet", "--bin", program, "--", *args]
    subprocess.run(cmd, cwd=ROOT, env=env, check=True, capture_output=True, text=True)
    return out_dir


def summary(path):
    return json.loads(pathlib.Path(path).read_text())


@pytest.fixture(scope="session")
def root():
    return ROOT
