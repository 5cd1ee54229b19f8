"""Shared fixtures: the repository's root (for its examples) and the `lsdc` command line the
package's results are compared with (``LSDC_BIN``, else ``target/{debug,release}/lsdc``)."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def example(root):
    return lambda name: str(root / "examples" / name)


@pytest.fixture(scope="session")
def lsdc_bin(root):
    """The command line, or a skip (a failure with CI set) where it is not built."""
    candidates = [os.environ.get("LSDC_BIN")] + [
        str(root / "target" / profile / "lsdc") for profile in ("debug", "release")
    ]
    for candidate in candidates:
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    why = "no lsdc binary: build it (cargo build --bin lsdc) or set LSDC_BIN"
    if os.environ.get("CI"):
        pytest.fail(why)
    pytest.skip(why)


@pytest.fixture(scope="session")
def run_cli(lsdc_bin):
    """Runs `lsdc ARGS...`: its standard output (the command must succeed)."""

    def run(*args):
        done = subprocess.run([lsdc_bin, *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, f"lsdc {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout

    return run
