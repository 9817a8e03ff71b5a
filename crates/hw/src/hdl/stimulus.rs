//! Test vectors: the input stream (corners, then random inputs with bubbles), the
//! outputs the Rust model expects on every clock, and the file the testbench reads.

use std::path::Path;

use rayon::prelude::*;

use super::{mask, HdlUnit, Ports, ToolError};
use crate::{Input, Output};

/// One clock in every `BUBBLE_ONE_IN` has `in_valid` low, so the valid bits and the
/// latency are exercised with gaps in the stream.
const BUBBLE_ONE_IN: u64 = 16;

/// Steps of the `cos` code either side of each `n`'s zero crossing of the K_v base
/// (where `1 - a(n)(1 - c)` changes sign and SW starts to output 0).
const ZERO_CROSSING_STEPS: i64 = 3;

/// A deterministic generator (splitmix64, Steele et al. 2014). Hand-written: eight lines
/// that make the vectors reproducible from a seed on every platform, which is all the
/// testbench needs; no dependency's version can change the stream.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..=max` (the modulo bias is below 2^-40 for the ranges used).
    fn upto(&mut self, max: u64) -> u64 {
        self.next() % (max + 1)
    }
}

/// The input stream of one co-simulation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stimulus {
    /// One entry per clock; `None` is a clock with `in_valid` low.
    pub stream: Vec<Option<Input>>,
    /// Inputs that are corner cases (the first ones of the stream).
    pub corners: usize,
}

impl Stimulus {
    /// Valid inputs in the stream.
    pub fn vectors(&self) -> usize {
        self.stream.iter().filter(|i| i.is_some()).count()
    }
}

/// The corner inputs: `cos` at -2, -1, 0, 1 and the codes beside them, and the largest
/// code; `n` at 0, 1, 2, `2^v - 1`, `2^v`, `2^v + 1` and the largest two; `k_s·I` at 0,
/// full scale and a mix; then, for every `n`, the codes around the zero crossing of the
/// K_v base `1 - a(n)(1 - c)` for `a(n) = (n+1)/(2^v+1)`.
fn corners(ports: Ports, v: u32) -> Vec<Input> {
    let f = ports.cos_bits - 2;
    let one = 1i64 << f;
    let (lo, hi) = (
        -(1i64 << (ports.cos_bits - 1)),
        (1i64 << (ports.cos_bits - 1)) - 1,
    );
    let nmax = mask(ports.n_bits) as u32;
    let fs = mask(ports.out_bits);
    let cos_codes = [
        lo,
        -one - 1,
        -one,
        -one + 1,
        -1,
        0,
        1,
        2,
        one - 2,
        one - 1,
        one,
        one + 1,
        hi,
    ];
    let p = 1u32 << v;
    let mut ns = vec![0, 1, 2, p.saturating_sub(1), p, p + 1, nmax - 1, nmax];
    ns.retain(|&n| n <= nmax);
    let kss = [[0, 0, 0], [fs, fs, fs], [1, fs / 2, fs]];
    let mut out = Vec::new();
    for &n in &ns {
        for &cos in &cos_codes {
            for &ks in &kss {
                out.push(Input { cos, n, ks });
            }
        }
    }
    // Zero crossings: t = 1 - c = 1/a(n) = (2^v + 1)/(n + 1), as a code 2^f·t.
    for n in 0..=nmax {
        let t = ((one as i128) * i128::from(p + 1) / i128::from(n + 1)) as i64;
        for d in -ZERO_CROSSING_STEPS..=ZERO_CROSSING_STEPS {
            let cos = (one - t + d).clamp(lo, hi);
            out.push(Input {
                cos,
                n,
                ks: [fs, fs, fs],
            });
        }
    }
    out
}

/// The input stream: every corner (see the module), then random inputs until `vectors`
/// valid inputs (or just the corners if there are more of them), with one clock in
/// `BUBBLE_ONE_IN` (16) a bubble. Half of the random `cos` codes are uniform over the whole
/// input range, half over `[0, 1]` where the lobes live. `v` places the corners
/// `n = 2^v` and the K_v zero crossings.
pub fn stimulus(ports: Ports, v: u32, vectors: usize, seed: u64) -> Stimulus {
    let mut rng = SplitMix(seed);
    let corners = corners(ports, v);
    let n_corners = corners.len();
    let f = ports.cos_bits - 2;
    let span = mask(ports.cos_bits);
    let half = 1i64 << (ports.cos_bits - 1);
    let mut stream = Vec::with_capacity(vectors + vectors / 8 + 16);
    let mut valid = 0usize;
    let mut corner_iter = corners.into_iter();
    while valid < vectors.max(n_corners) {
        if rng.upto(BUBBLE_ONE_IN - 1) == 0 {
            stream.push(None);
            continue;
        }
        let input = corner_iter.next().unwrap_or_else(|| {
            let cos = if rng.next() & 1 == 0 {
                rng.upto(span) as i64 - half
            } else {
                rng.upto(1u64 << f) as i64
            };
            Input {
                cos,
                n: rng.upto(mask(ports.n_bits)) as u32,
                ks: [0; 3].map(|_| rng.upto(mask(ports.out_bits))),
            }
        });
        stream.push(Some(input));
        valid += 1;
    }
    Stimulus {
        stream,
        corners: n_corners,
    }
}

/// The stream with `latency` bubbles appended (so every result leaves the pipeline),
/// and the outputs the unit's cycle model gives after each clock edge.
pub fn expected_stream<U: HdlUnit + ?Sized>(
    unit: &U,
    stimulus: &Stimulus,
) -> (Vec<Option<Input>>, Vec<Option<Output>>) {
    let mut stream = stimulus.stream.clone();
    stream.extend(std::iter::repeat_n(None, unit.latency() as usize));
    let expected = unit.cycle_model(&stream);
    (stream, expected)
}

/// Writes the vector file the testbench reads: one line per clock, in hexadecimal,
/// `in_valid cos n ks_r ks_g ks_b out_valid r g b` (the expected outputs after that
/// clock's edge; `x` where the output is not valid). `cos` is the two's complement
/// code in `cos_bits` bits.
pub fn write_vectors<U: HdlUnit + ?Sized>(
    unit: &U,
    stimulus: &Stimulus,
    path: &Path,
) -> Result<usize, ToolError> {
    let ports = unit.ports();
    let (stream, expected) = expected_stream(unit, stimulus);
    glint_io::write_atomic(path, |w| {
        for (input, out) in stream.iter().zip(&expected) {
            match input {
                Some(i) => write!(
                    w,
                    "1 {:x} {:x} {:x} {:x} {:x} ",
                    i.cos as u64 & mask(ports.cos_bits),
                    i.n,
                    i.ks[0],
                    i.ks[1],
                    i.ks[2]
                )?,
                None => write!(w, "0 0 0 0 0 0 ")?,
            }
            match out {
                Some(o) => writeln!(w, "1 {:x} {:x} {:x}", o.rgb[0], o.rgb[1], o.rgb[2])?,
                None => writeln!(w, "0 0 0 0")?,
            }
        }
        Ok(())
    })?;
    Ok(stream.len())
}

/// See [`HdlUnit::max_error_vs_power`].
pub(crate) fn max_error_vs_power<U: HdlUnit + ?Sized>(unit: &U) -> f64 {
    let ports = unit.ports();
    let one = 1i64 << (ports.cos_bits - 2);
    let fs = mask(ports.out_bits);
    (0..=mask(ports.n_bits) as u32)
        .into_par_iter()
        .map(|n| {
            let mut worst = 0.0f64;
            for cos in 0..=one {
                let out = unit
                    .eval(&Input {
                        cos,
                        n,
                        ks: [fs; 3],
                    })
                    .rgb[0];
                let exact = fs as f64 * (cos as f64 / one as f64).powi(n as i32);
                worst = worst.max((out as f64 - exact).abs());
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}
