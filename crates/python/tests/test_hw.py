"""glint.hw.Unit against `glint hw eval` and the K_v formula."""

import json
import pickle
import threading

import numpy as np
import pytest

import glint
from conftest import cli_error_line, run_glint


def cli_rgb(glint_bin, code, n, ks, config=None):
    """The R, G, B codes `glint hw eval` prints for one input (rows MUL1 R .. MUL3 B)."""
    args = ["hw", "eval", "--cos-code", str(code), "--n", str(n), "--ks-rgb", ",".join(map(str, ks))]
    if config:
        args += ["--config", config]
    proc = run_glint(glint_bin, *args)
    assert proc.returncode == 0, proc.stderr
    rgb = []
    for name in ("MUL1 R", "MUL2 G", "MUL3 B"):
        line = next(l for l in proc.stdout.splitlines() if l.startswith(name))
        tokens = line.split()
        hex_at = next(i for i, t in enumerate(tokens) if t.startswith("0x"))
        rgb.append(int(tokens[hex_at - 1]))
    return rgb


def test_default_unit_matches_cli(glint_bin):
    unit = glint.hw.Unit()
    codes = np.array([16384, 16200, 16057, 15000, 0, -16384], dtype=np.int64)
    for n in (1, 100, 1023):
        got = unit.eval(codes, n, (255, 200, 180))
        assert got.shape == (6, 3) and got.dtype == np.uint64
        for code, rgb in zip(codes, got):
            assert list(rgb) == cli_rgb(glint_bin, code, n, (255, 200, 180))


def test_config_file_matches_cli(glint_bin, tmp_path):
    cfg = {"v": 3, "square_frac": [16, 16, 14], "out_bits": 10, "coefficients": "minimax"}
    path = tmp_path / "unit.json"
    path.write_text(json.dumps(cfg))
    unit = glint.hw.Unit(cfg)
    assert unit.config["v"] == 3 and unit.latency == 7 and unit.full_scale == 1023
    assert glint.hw.Unit(json.dumps(cfg)).config == unit.config
    got = unit.eval(np.array([16300, 16000]), np.array([50, 700]), (1023, 512, 1))
    assert list(got[0]) == cli_rgb(glint_bin, 16300, 50, (1023, 512, 1), str(path))
    assert list(got[1]) == cli_rgb(glint_bin, 16000, 700, (1023, 512, 1), str(path))


def test_default_unit_within_one_lsb_of_k4():
    # docs/hardware.md: the default configuration stays within 0.6235 LSB of the exact
    # K_4 at 8 bits; K_4(n, c) = max(0, 1 - (n+1)/17 (1 - c))^16 (the paper's lobe).
    unit = glint.hw.Unit()
    cos = np.linspace(0.9, 1.0, 2001)
    codes = unit.cos_codes(cos)
    assert codes.dtype == np.int64 and codes.shape == cos.shape
    c = codes / 2.0**14
    for n in (10, 100, 500, 1023):
        k4 = np.maximum(0.0, 1.0 - (n + 1) / 17 * (1.0 - c)) ** 16
        out = unit.eval(codes, n, (255, 255, 255))[:, 0].astype(np.float64)
        assert np.max(np.abs(out - 255 * k4)) <= 0.6235 + 1e-9


def test_bad_inputs_raise(glint_bin):
    unit = glint.hw.Unit()
    with pytest.raises(ValueError) as err:
        glint.hw.Unit({"v": 11})
    assert str(err.value) == "invalid configuration: v = 11; expected 0..=10 (BMUL has v squaring stages, power 2^v <= 1024)"
    with pytest.raises(ValueError, match="unknown field"):
        glint.hw.Unit({"width": 3})
    with pytest.raises(TypeError):
        glint.hw.Unit(4)
    with pytest.raises(ValueError, match="element 1: .*n = 1024 does not fit 10 bits"):
        unit.eval(np.array([0, 0]), np.array([1, 1024]), (1, 1, 1))
    with pytest.raises(ValueError, match="outside the 16-bit signed range"):
        unit.eval(40000, 5, (1, 1, 1))
    with pytest.raises(ValueError, match="does not fit 8 bits"):
        unit.eval(0, 5, (256, 1, 1))
    with pytest.raises(TypeError, match="integer codes"):
        unit.eval(np.array([0.5]), 5, (1, 1, 1))
    with pytest.raises(ValueError, match="not contiguous"):
        unit.eval(np.arange(10)[::2], 5, (1, 1, 1))
    with pytest.raises(ValueError, match="shape"):
        unit.eval(np.arange(10), np.arange(3), (1, 1, 1))
    with pytest.raises(ValueError) as err:
        unit.cos_codes(2.0)
    assert str(err.value) == cli_error_line(glint_bin, "hw", "eval", "--cos", "2.0")


def test_pickle_and_threads():
    unit = pickle.loads(pickle.dumps(glint.hw.Unit({"v": 5, "square_frac": [14, 14, 14, 14, 12]})))
    assert unit.config["v"] == 5
    codes = np.arange(-16384, 16384, dtype=np.int32)
    want = unit.eval(codes, 300, (255, 128, 7))
    got = [None] * 4

    def work(i):
        got[i] = unit.eval(codes, 300, (255, 128, 7))

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for g in got:
        np.testing.assert_array_equal(g, want)
