"""Shared fixtures: the sample data and the glint command, both external to the package.

A test that needs one of them fails when it is missing and CI is set, and is skipped
with the reason otherwise (the project's rule for external tools and data).
"""

import json
import os
import pathlib
import subprocess

import pytest

SAMPLES = pathlib.Path(os.environ.get("GLINT_DATA", pathlib.Path.home() / ".cache" / "glint")) / "samples"
MNI152 = SAMPLES / "mni152_t1_09a.nii.gz"


def _missing(what: str):
    if os.environ.get("CI"):
        pytest.fail(f"{what} (CI is set, so this is a failure)")
    pytest.skip(what)


@pytest.fixture(scope="session")
def mni_path() -> pathlib.Path:
    if not MNI152.is_file():
        _missing(f"{MNI152} is missing: run scripts/fetch-samples")
    return MNI152


@pytest.fixture(scope="session")
def glint_bin() -> str:
    """The glint command (GLINT_BIN, as scripts/test-python sets it)."""
    path = os.environ.get("GLINT_BIN")
    if not path or not os.access(path, os.X_OK):
        _missing(f"GLINT_BIN={path!r} is not an executable: build it with cargo build -p glint-cli")
    return path


def run_glint(glint_bin: str, *args: str) -> subprocess.CompletedProcess:
    """Runs the glint command, capturing its output as text."""
    return subprocess.run([glint_bin, *args], capture_output=True, text=True, timeout=300)


def glint_json(glint_bin: str, *args: str):
    """Runs a glint command with JSON output and parses it."""
    proc = run_glint(glint_bin, *args)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def cli_error_line(glint_bin: str, *args: str) -> str:
    """The one-line error a failing glint command prints, without its 'glint: error: '."""
    proc = run_glint(glint_bin, *args)
    assert proc.returncode != 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    prefix = "glint: error: "
    assert lines[0].startswith(prefix), lines[0]
    return lines[0][len(prefix):]
