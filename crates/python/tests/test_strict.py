"""The strictness rule of the Python tests is the Rust one (crates/testkit)."""

import conftest


def test_false_spellings_are_the_shared_file():
    assert conftest.false_values() == {"0", "false", "no", "off"}


def test_is_true_matches_the_rust_table():
    # The same table as crates/testkit/src/lib.rs `true_and_false_spellings`.
    for v in ["1", "true", "TRUE", "yes", "on", " 1 ", "anything"]:
        assert conftest.is_true(v), v
    for v in [None, "", " ", "0", "false", "False", "no", "NO", "off", "Off"]:
        assert not conftest.is_true(v), v


def test_strict_reads_both_variables(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    monkeypatch.delenv("GLINT_STRICT", raising=False)
    assert not conftest.strict()
    monkeypatch.setenv("CI", "false")
    assert not conftest.strict()
    monkeypatch.setenv("GLINT_STRICT", "1")
    assert conftest.strict()
    monkeypatch.delenv("GLINT_STRICT")
    monkeypatch.setenv("CI", "true")
    assert conftest.strict()
