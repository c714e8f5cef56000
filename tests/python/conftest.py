"""Shared by the Python tests: the mbsflow program of this build (MBSFLOW_EXE, set by
ctest), run as a user runs it."""
import os
import subprocess

import pytest

EXE = os.environ.get("MBSFLOW_EXE", "mbsflow")
SOURCE = os.environ.get("MBSFLOW_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))


def cli(*args, check=True):
    """Runs `mbsflow ARGS`; returns (exit code, stdout, stderr)."""
    p = subprocess.run([EXE, *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"mbsflow {' '.join(map(str, args))} exited {p.returncode}: {p.stderr}")
    return p.returncode, p.stdout, p.stderr


@pytest.fixture
def source():
    return SOURCE
