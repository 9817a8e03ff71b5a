"""glint.lobe against `glint eval --json` (same f64 code path) and the lobe formulas."""

import threading

import numpy as np
import pytest

import glint
from conftest import cli_error_line, glint_json

KINDS = ["exact", "k", "g", "schlick", "gauss", "minimax"]
COS = [1.0, 0.9999, 0.999, 0.995, 0.99, 0.98, 0.95, 0.9, 0.7, 0.3, 0.0, -0.5, -1.0]


@pytest.mark.parametrize("n,v", [(100.0, 4), (10.0, 2), (1000.0, 6)])
def test_float64_equals_glint_eval(glint_bin, n, v):
    doc = glint_json(
        glint_bin, "eval", "--json", "--n", str(n), "--v", str(v),
        "--lobe", ",".join(KINDS), "--cos", ",".join(map(repr, COS)),
    )
    cos = np.array([row["cos"] for row in doc["rows"]])
    for kind in KINDS:
        want = np.array([row[kind] for row in doc["rows"]])
        got = glint.lobe(kind, cos, n, v)
        assert got.dtype == np.float64
        # Same f64 evaluation on both sides: bit for bit.
        np.testing.assert_array_equal(got, want, err_msg=kind)


def power_fit(cos, a, v):
    """max(0, 1 - a (1 - c))^(2^v), the power form of K_v, G_v and the minimax fit."""
    return np.maximum(0.0, 1.0 - a * (1.0 - cos)) ** (2**v)


@pytest.mark.parametrize("n,v", [(100.0, 4), (37.0, 3), (800.0, 8)])
def test_float32_simd_matches_formulas(n, v):
    cos = np.linspace(-1.0, 1.0, 100_003, dtype=np.float32)  # not a multiple of a lane count
    c = cos.astype(np.float64)
    formulas = {
        # Pavlov, Romanyuk and Dumenko: a = (n+1)/(2^v+1); Lyon 1993: a = n/2^v.
        "k": power_fit(c, (n + 1) / (2**v + 1), v),
        "g": power_fit(c, n / 2**v, v),
        "exact": np.maximum(c, 0.0) ** n,
        "schlick": np.where(c > 0, c / (n * (1 - c) + c), 0.0),
        "gauss": np.exp(n * (c - 1)),
    }
    for kind, want in formulas.items():
        got = glint.lobe(kind, cos, n, v)
        assert got.dtype == np.float32 and got.shape == cos.shape
        # float32 rounding of a^(2^v)-style chains: a few ulp relative, 1e-6 absolute.
        np.testing.assert_allclose(got, want, rtol=2e-5 * 2**v, atol=1e-6, err_msg=kind)


def test_float32_equals_float64_reference_power_fits():
    # The power fits' SIMD kernels give exactly the scalar eval's f32 values, which are
    # the f64 values rounded through the same f32 steps: compare to f32 numpy.
    cos = np.linspace(0.5, 1.0, 4097, dtype=np.float32)
    a = np.float32((100 + 1) / (2**4 + 1))
    b = np.maximum(np.float32(0), np.float32(1) - a * (np.float32(1) - cos))
    for _ in range(4):
        b = b * b
    np.testing.assert_array_equal(glint.lobe("k", cos, 100, 4), b)


def test_shape_order_and_scalar():
    cos = np.asfortranarray(np.linspace(0, 1, 24, dtype=np.float64).reshape(2, 3, 4))
    got = glint.lobe("exact", cos, 2.0)
    assert got.shape == (2, 3, 4)
    np.testing.assert_allclose(got, cos**2, rtol=1e-15)
    assert glint.lobe("exact", 0.5, 2.0) == 0.25
    assert glint.lobe("k", np.array(0.5), 2.0).shape == ()  # 0-D array in, 0-D array out
    assert glint.lobe_kinds() == KINDS


def test_bad_inputs_raise():
    cos = np.linspace(0, 1, 10)
    with pytest.raises(TypeError, match="float32 or float64"):
        glint.lobe("k", np.arange(10), 100)
    with pytest.raises(TypeError, match="numpy array"):
        glint.lobe("k", [0.5, 0.9], 100)
    with pytest.raises(ValueError, match="not contiguous"):
        glint.lobe("k", cos[::2], 100)
    with pytest.raises(ValueError, match="invalid shininess"):
        glint.lobe("k", cos, float("nan"))
    with pytest.raises(ValueError, match="invalid v"):
        glint.lobe("k", cos, 100, 11)
    with pytest.raises(OverflowError):
        glint.lobe("k", cos, 100, -1)


def test_messages_equal_the_cli(glint_bin):
    for args, call in [
        (["--lobe", "phong2"], lambda: glint.lobe("phong2", np.ones(1), 100)),
        (["--n", "-3"], lambda: glint.lobe("k", np.ones(1), -3)),
        (["--v", "12"], lambda: glint.lobe("k", np.ones(1), 100, 12)),
    ]:
        line = cli_error_line(glint_bin, "eval", *args)
        with pytest.raises(ValueError) as err:
            call()
        assert str(err.value) == line


def test_threads():
    rng = np.random.default_rng(1)
    inputs = [rng.uniform(-1, 1, 200_000).astype(np.float32) for _ in range(8)]
    want = [glint.lobe("minimax", c, 300, 5) for c in inputs]
    got = [None] * len(inputs)

    def work(i):
        for _ in range(5):
            got[i] = glint.lobe("minimax", inputs[i], 300, 5)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(inputs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, w)
