//! The field's arithmetic, written once for the pass over the whole volume
//! ([`super::prepare`]) and the bricks ([`super::brick`]): the binomial prefilter on a
//! box, world gradients by central differences, and their 16-bit quantisation. Both
//! callers do the same float operations in the same order on the same inputs, so a
//! brick's values and gradients are bit for bit those of a whole-volume pass.

/// The `[1 2 1] / 4` binomial along x, y and z in turn ([`super::Prefilter::Binomial`])
/// of the box `src` (`size`, i fastest), whose outer layer is padding: the result is
/// the inner box, `size - 2` per axis. The volume's faces are clamped by the caller
/// padding with copies of the face (a face voxel then counts its missing neighbour as
/// itself, as the whole-volume filter did); each output is
/// `0.25 a + 0.5 b + 0.25 c`, evaluated left to right, x first, then y, then z.
#[cfg(test)]
pub(super) fn binomial_box(src: &[f32], size: [usize; 3]) -> Vec<f32> {
    let mut out = Vec::new();
    binomial_box_into(src, size, &mut out, &mut Vec::new());
    out
}

/// [`binomial_box`] into `out` (resized to the inner box; its old contents are all
/// overwritten), one slice at a time: each slice of `src` filtered along x and y into
/// a ring of three in `scratch`, and each output slice along z from the ring as soon
/// as its three inputs are there. The same operations on the same values as three
/// whole-box passes, so the same bits; but the only memory it touches besides `src`
/// and `out` is four slices, and both buffers are the caller's to reuse (fresh pages
/// for whole-box temporaries per slab were most of the pass before the first frame).
pub(super) fn binomial_box_into(
    src: &[f32],
    size: [usize; 3],
    out: &mut Vec<f32>,
    scratch: &mut Vec<f32>,
) {
    let [sx, sy, sz] = size;
    debug_assert!(sx >= 3 && sy >= 3 && sz >= 3 && src.len() == sx * sy * sz);
    let (ox, oy, oz) = (sx - 2, sy - 2, sz - 2);
    let plane = ox * oy;
    out.resize(plane * oz, 0.0);
    // One slice along x, then three slices along x and y (a ring indexed by k mod 3).
    scratch.resize(ox * sy + 3 * plane, 0.0);
    let (x, ring) = scratch.split_at_mut(ox * sy);
    for (k, slice) in src.chunks_exact(sx * sy).enumerate() {
        // Along x: every row of the slice.
        for (o, r) in x.chunks_exact_mut(ox).zip(slice.chunks_exact(sx)) {
            for (i, o) in o.iter_mut().enumerate() {
                *o = 0.25 * r[i] + 0.5 * r[i + 1] + 0.25 * r[i + 2];
            }
        }
        // Along y: rows 1..sy-1.
        let y = &mut ring[plane * (k % 3)..][..plane];
        for (j, o) in y.chunks_exact_mut(ox).enumerate() {
            let row = |jj: usize| &x[ox * jj..][..ox];
            mix(o, row(j), row(j + 1), row(j + 2));
        }
        // Along z: output slice k - 2 from y slices k - 2, k - 1, k.
        if k >= 2 {
            let sl = |kk: usize| &ring[plane * (kk % 3)..][..plane];
            mix(
                &mut out[plane * (k - 2)..][..plane],
                sl(k - 2),
                sl(k - 1),
                sl(k),
            );
        }
    }
}

/// `out = 0.25 a + 0.5 b + 0.25 c` elementwise (vectorises).
#[inline(always)]
fn mix(out: &mut [f32], a: &[f32], b: &[f32], c: &[f32]) {
    for (((o, &a), &b), &c) in out.iter_mut().zip(a).zip(b).zip(c) {
        *o = 0.25 * a + 0.5 * b + 0.25 * c;
    }
}

/// One row's neighbours for [`row_gradients`]: the rows before and after along j and
/// k, and the divisor of each difference (2 for central differences, 1 for the
/// one-sided ones at the volume's faces, where the missing row is the row itself).
pub(super) struct Neighbours<'a> {
    pub(super) jm: &'a [f32],
    pub(super) jp: &'a [f32],
    pub(super) span_j: f32,
    pub(super) km: &'a [f32],
    pub(super) kp: &'a [f32],
    pub(super) span_k: f32,
}

/// World gradients of the voxels `c[lo..hi]` of a row into `out` (`hi - lo` long):
/// central differences in index space (one-sided at the volume's faces: `face_lo`
/// when `c[lo]` is the volume's first voxel along i, `face_hi` when `c[hi - 1]` is
/// its last), mapped by `g` (the inverse transpose of the affine's 3x3 part). Voxels
/// away from the faces read `c[i - 1]` and `c[i + 1]`, so `c` must reach one voxel
/// beyond `lo..hi` on each side that is not a face.
pub(super) fn row_gradients(
    c: &[f32],
    n: &Neighbours,
    (lo, hi): (usize, usize),
    (face_lo, face_hi): (bool, bool),
    g: &[[f32; 3]; 3],
    out: &mut [[f32; 3]],
) {
    let world = |gi: f32, gj: f32, gk: f32| {
        [
            g[0][0] * gi + g[0][1] * gj + g[0][2] * gk,
            g[1][0] * gi + g[1][1] * gj + g[1][2] * gk,
            g[2][0] * gi + g[2][1] * gj + g[2][2] * gk,
        ]
    };
    let (sj, sk) = (n.span_j, n.span_k);
    let at = |i: usize| {
        let gi = if face_lo && i == lo {
            (c[i + 1] - c[i]) / 1.0
        } else if face_hi && i + 1 == hi {
            (c[i] - c[i - 1]) / 1.0
        } else {
            (c[i + 1] - c[i - 1]) / 2.0
        };
        world(gi, (n.jp[i] - n.jm[i]) / sj, (n.kp[i] - n.km[i]) / sk)
    };
    let first = lo + usize::from(face_lo);
    let last = hi - usize::from(face_hi);
    if face_lo {
        out[0] = at(lo);
    }
    if face_hi && hi > first {
        out[hi - 1 - lo] = at(hi - 1);
    }
    // The interior without the face tests, in the same operations as `at`.
    for i in first..last.max(first) {
        let gi = (c[i + 1] - c[i - 1]) / 2.0;
        out[i - lo] = world(gi, (n.jp[i] - n.jm[i]) / sj, (n.kp[i] - n.km[i]) / sk);
    }
}

/// [`row_gradients`] and [`quantise`] of each component into `out`, for a `g` whose
/// only non-zero entries are its diagonal `d`, and values whose differences are finite
/// (the caller bounds them): the same stored gradients bit for bit, without the
/// matrix. World component a is `d[a] * g_a` plus two products `0 * g_b`, each a zero
/// (the differences are finite), and adding a zero changes at most the sign of a zero
/// result; both signs of zero, and every other value, quantise alike. The differences
/// are `row_gradients`'s, in the same operations. (The matrix and a second loop over
/// the row to quantise were half of a brick's build, issue 47.)
pub(super) fn row_quantised_diagonal(
    c: &[f32],
    n: &Neighbours,
    (lo, hi): (usize, usize),
    (face_lo, face_hi): (bool, bool),
    d: [f32; 3],
    inv_scale: f32,
    out: &mut [[i16; 4]],
) {
    let (sj, sk) = (n.span_j, n.span_k);
    let q = |x: f32| quantise(x, inv_scale);
    let put = |i: usize, gi: f32| {
        [
            q(d[0] * gi),
            q(d[1] * ((n.jp[i] - n.jm[i]) / sj)),
            q(d[2] * ((n.kp[i] - n.km[i]) / sk)),
            0,
        ]
    };
    let first = lo + usize::from(face_lo);
    let last = hi - usize::from(face_hi);
    if face_lo {
        out[0] = put(lo, (c[lo + 1] - c[lo]) / 1.0);
    }
    if face_hi && hi > first {
        out[hi - 1 - lo] = put(hi - 1, (c[hi - 1] - c[hi - 2]) / 1.0);
    }
    for i in first..last.max(first) {
        out[i - lo] = put(i, (c[i + 1] - c[i - 1]) / 2.0);
    }
}

/// A world gradient component in units of `1 / inv_scale`, rounded half away from zero
/// (without libm's roundf, a call per component on baseline x86-64); `|x| * inv_scale
/// <= 32767` up to rounding, and `as` saturates.
#[inline(always)]
pub(super) fn quantise(x: f32, inv_scale: f32) -> i16 {
    let y = x * inv_scale;
    (y + 0.5f32.copysign(y)) as i16
}

/// The quantisation step of the gradients for a volume whose largest gradient component
/// is `largest`: the largest maps to 32767.
pub(super) fn gradient_scale(largest: f32) -> f32 {
    if largest > 0.0 && largest.is_finite() {
        largest / 32767.0
    } else {
        1.0
    }
}

/// The divisor of a difference along an axis of `n` voxels at index `i`, and the
/// indices of the two samples it takes (one-sided at the faces).
#[inline(always)]
pub(super) fn span(i: usize, n: usize) -> (usize, usize, f32) {
    let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
    (a, b, (b - a) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference the whole-volume code used before bricks (kept here as the
    /// oracle): the binomial with clamped faces on a whole volume.
    fn binomial_whole(values: &[f32], dims: [usize; 3]) -> Vec<f32> {
        let [nx, ny, nz] = dims;
        let at = |v: &[f32], i: usize, j: usize, k: usize| v[i + nx * (j + ny * k)];
        let mut cur = values.to_vec();
        for axis in 0..3 {
            let mut next = vec![0.0f32; cur.len()];
            for k in 0..nz {
                for j in 0..ny {
                    for i in 0..nx {
                        let p = [i, j, k];
                        let n = dims[axis];
                        let mut lo = p;
                        let mut hi = p;
                        lo[axis] = p[axis].saturating_sub(1);
                        hi[axis] = (p[axis] + 1).min(n - 1);
                        next[i + nx * (j + ny * k)] = 0.25 * at(&cur, lo[0], lo[1], lo[2])
                            + 0.5 * at(&cur, i, j, k)
                            + 0.25 * at(&cur, hi[0], hi[1], hi[2]);
                    }
                }
            }
            cur = next;
        }
        cur
    }

    /// A volume of `dims` padded with copies of its faces, as the field reads boxes.
    fn padded(v: &[f32], dims: [usize; 3]) -> Vec<f32> {
        let size = dims.map(|d| d + 2);
        let mut out = Vec::new();
        for k in 0..size[2] {
            for j in 0..size[1] {
                for i in 0..size[0] {
                    let c = |x: usize, n: usize| x.saturating_sub(1).min(n - 1);
                    let (a, b, d) = (c(i, dims[0]), c(j, dims[1]), c(k, dims[2]));
                    out.push(v[a + dims[0] * (b + dims[1] * d)]);
                }
            }
        }
        out
    }

    fn samples(n: usize, seed: usize) -> Vec<f32> {
        (0..n)
            .map(|i| (((i + seed) * 7919 % 97) as f32).sqrt())
            .collect()
    }

    #[test]
    fn a_padded_box_filters_as_the_whole_volume() {
        let dims = [6, 5, 4];
        let v = samples(120, 0);
        let whole = binomial_whole(&v, dims);
        let boxed = binomial_box(&padded(&v, dims), dims.map(|d| d + 2));
        assert_eq!(boxed.len(), whole.len());
        for (i, (a, b)) in boxed.iter().zip(&whole).enumerate() {
            assert_eq!(a.to_bits(), b.to_bits(), "voxel {i}");
        }
    }

    /// Buffers reused from a larger box, a smaller one and a box of another shape
    /// (their stale contents must not show) give the whole-volume filter's bits.
    #[test]
    fn reused_buffers_filter_as_the_whole_volume() {
        let (mut out, mut scratch) = (Vec::new(), Vec::new());
        for (seed, dims) in [[7, 6, 5], [2, 3, 1], [9, 4, 6], [1, 1, 1]]
            .into_iter()
            .enumerate()
        {
            let v = samples(dims.iter().product(), seed * 13);
            binomial_box_into(
                &padded(&v, dims),
                dims.map(|d| d + 2),
                &mut out,
                &mut scratch,
            );
            let whole = binomial_whole(&v, dims);
            assert_eq!(out.len(), whole.len(), "{dims:?}");
            for (i, (a, b)) in out.iter().zip(&whole).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "{dims:?} voxel {i}");
            }
        }
    }

    /// The fused diagonal row gives the general row's quantised gradients, bit for bit:
    /// rows with and without faces, spans of 1 and 2, negative and tiny diagonals,
    /// equal neighbours (zero differences of either sign), and large values.
    #[test]
    fn diagonal_rows_quantise_as_the_matrix() {
        let m = 23;
        let row = |seed: usize, scale: f32| -> Vec<f32> {
            (0..m)
                .map(|i| match (i + seed) % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    _ => samples(1, i * 31 + seed)[0] * scale - scale,
                })
                .collect()
        };
        for (d, scale) in [
            ([1.0f32, 1.0, 1.0], 1.0f32),
            ([-1.0, 0.5, 2.0], 300.0),
            ([0.7, -1.3, 1e-3], 1e30),
            ([1e20, 1.0, -1.0], 1e-30),
        ] {
            let g = [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]];
            let c = row(0, scale);
            let (jm, jp, km) = (row(1, scale), row(2, scale), row(3, scale));
            for (span_j, span_k, kp) in [(2.0, 2.0, row(4, scale)), (1.0, 2.0, c.clone())] {
                let n = Neighbours {
                    jm: &jm,
                    jp: &jp,
                    span_j,
                    km: &km,
                    kp: &kp,
                    span_k,
                };
                for (lo, hi, faces) in [
                    (0, m, (true, true)),
                    (1, m - 1, (false, false)),
                    (0, 9, (true, false)),
                    (5, m, (false, true)),
                ] {
                    let inv = 1.0 / gradient_scale(3.0 * scale);
                    let mut w = vec![[0.0f32; 3]; hi - lo];
                    row_gradients(&c, &n, (lo, hi), faces, &g, &mut w);
                    let want: Vec<[i16; 4]> = w
                        .iter()
                        .map(|w| {
                            [
                                quantise(w[0], inv),
                                quantise(w[1], inv),
                                quantise(w[2], inv),
                                0,
                            ]
                        })
                        .collect();
                    let mut got = vec![[9i16; 4]; hi - lo];
                    row_quantised_diagonal(&c, &n, (lo, hi), faces, d, inv, &mut got);
                    assert_eq!(got, want, "{d:?} {scale} {lo}..{hi}");
                }
            }
        }
    }

    #[test]
    fn quantisation_rounds_half_away_from_zero_and_saturates() {
        assert_eq!(quantise(2.5, 1.0), 3);
        assert_eq!(quantise(-2.5, 1.0), -3);
        assert_eq!(quantise(2.49, 1.0), 2);
        assert_eq!(quantise(1e9, 1.0), i16::MAX);
        assert_eq!(gradient_scale(32767.0), 1.0);
        assert_eq!(gradient_scale(0.0), 1.0);
        assert_eq!(gradient_scale(f32::INFINITY), 1.0);
        assert_eq!(span(0, 4), (0, 1, 1.0));
        assert_eq!(span(2, 4), (1, 3, 2.0));
        assert_eq!(span(3, 4), (2, 3, 1.0));
    }
}
