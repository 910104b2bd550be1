"""Shared fixtures: the repository's test images and the command-line program."""

import os
import pathlib
import shutil

import pytest

import ocellus

ROOT = pathlib.Path(__file__).resolve().parents[2]
TESTDATA = ROOT / "testdata"


@pytest.fixture(scope="session")
def photo():
    """The chelsea photo (451 x 300 RGB, uint8)."""
    return ocellus.read_image(TESTDATA / "chelsea.png")


@pytest.fixture(scope="session")
def cli():
    """The `ocellus` binary: $OCELLUS_BIN (scripts/test.sh sets it), else the workspace's build."""
    path = os.environ.get("OCELLUS_BIN")
    candidates = [path] if path else [ROOT / "target" / p / "ocellus" for p in ("release", "debug")]
    for c in candidates:
        if c and pathlib.Path(c).is_file():
            return str(c)
    found = shutil.which("ocellus")
    if found:
        return found
    pytest.fail(f"no ocellus binary (looked at {candidates}); build it with `cargo build -p ocellus-cli`")
