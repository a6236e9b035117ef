"""Shared fixtures: the repository root, the CLI binary and its outputs for the paper scene."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cli_binary() -> pathlib.Path:
    """The flexprr CLI built by tests/python/run.sh (FLEXPRR_BIN overrides)."""
    path = pathlib.Path(os.environ.get("FLEXPRR_BIN", ROOT / "target" / "release" / "flexprr"))
    if not path.exists():
        raise FileNotFoundError(f"{path}: build the CLI first (cargo build --release --bin flexprr)")
    return path


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    return cli_binary()


@pytest.fixture(scope="session")
def paper_cli_out(tmp_path_factory, cli) -> pathlib.Path:
    """The CLI's outputs of configs/paper_f20.toml."""
    out = tmp_path_factory.mktemp("cli") / "paper_f20"
    subprocess.run(
        [str(cli), "run", str(ROOT / "configs" / "paper_f20.toml"), "--out", str(out), "--quiet"],
        check=True,
        capture_output=True,
    )
    return out
