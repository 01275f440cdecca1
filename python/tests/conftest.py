"""Shared fixtures: the repository's paths and the era command line built beside."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def era_binary() -> pathlib.Path:
    """The CLI the Python results are compared with: $ERA_BIN, or the workspace's
    release build (scripts/python_tests.sh builds it)."""
    if os.environ.get("ERA_BIN"):
        return pathlib.Path(os.environ["ERA_BIN"])
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    if not target.is_absolute():
        target = REPO / target
    return target / "release" / "era"


@pytest.fixture(scope="session")
def era_cli():
    binary = era_binary()
    if not binary.exists():
        pytest.fail(
            f"{binary} is absent: build it with `cargo build --release -p era-cli` "
            "(scripts/python_tests.sh does) or set ERA_BIN"
        )

    def run(*args, check=True):
        done = subprocess.run(
            [str(binary), *map(str, args)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        if check and done.returncode != 0:
            raise AssertionError(f"era {' '.join(map(str, args))}: {done.stderr}")
        return done

    return run


@pytest.fixture(scope="session")
def data_dir() -> pathlib.Path:
    return REPO / "data"
