"""Shared fixtures: the sample data and the glint command, both external to the package.

A test that needs one of them fails when it is missing in strict mode (GLINT_STRICT or
CI set to a true value; the false spellings are crates/testkit/false-values.txt, which
the Rust tests read too), and is skipped with the reason otherwise (issue 34). Optional
paths that ran are appended to GLINT_PATHS_LOG, which scripts/test summarises.
"""

import json
import os
import pathlib
import subprocess

import pytest

SAMPLES = pathlib.Path(os.environ.get("GLINT_DATA") or pathlib.Path.home() / ".cache" / "glint") / "samples"
MNI152 = SAMPLES / "mni152_t1_09a.nii.gz"
FALSE_VALUES_FILE = pathlib.Path(__file__).resolve().parents[2] / "testkit" / "false-values.txt"


def false_values() -> set:
    """The spellings that leave strict mode off (besides unset), shared with Rust."""
    lines = (line.strip() for line in FALSE_VALUES_FILE.read_text().splitlines())
    return {line.lower() for line in lines if line and not line.startswith("#")}


def is_true(value) -> bool:
    """glint_testkit::is_true: None, blank and the shared false spellings are false."""
    if value is None or not value.strip():
        return False
    return value.strip().lower() not in false_values()


def strict() -> bool:
    """Whether a missing tool or sample fails (GLINT_STRICT or CI true)."""
    return is_true(os.environ.get("GLINT_STRICT")) or is_true(os.environ.get("CI"))


def record(line: str) -> None:
    """Appends one line to GLINT_PATHS_LOG (if set): what optional path ran or not."""
    log = os.environ.get("GLINT_PATHS_LOG")
    if log:
        with open(log, "a") as f:
            f.write(line + "\n")


def ran(what: str) -> None:
    """Records that the optional path `what` ran."""
    record(f"ran {what}")


def _missing(what: str):
    if strict():
        pytest.fail(f"missing: {what} (strict mode: GLINT_STRICT or CI is set)")
    record(f"SKIPPED {what}")
    pytest.skip(what)


def require_module(name: str):
    """Imports a module a test needs (a reference reader); missing: fail when strict."""
    try:
        module = __import__(name)
    except ImportError:
        _missing(f"Python module {name} (crates/python/tests/requirements.txt)")
    ran(f"python reference reader {name}")
    return module


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
