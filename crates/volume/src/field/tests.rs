//! The field's tests: the bricked, lazily built field against the whole-volume
//! computation it replaced (kept here as the oracle), bit for bit.

use super::*;
use glint_io::Samples;

fn linear_volume() -> Volume {
    // f(i, j, k) = 2i + 3j - k on a 4x5x6 grid with spacing (2, 1, 0.5) mm.
    let dims = [4, 5, 6];
    let mut v = Vec::new();
    for k in 0..6 {
        for j in 0..5 {
            for i in 0..4 {
                v.push((2 * i + 3 * j) as f32 - k as f32);
            }
        }
    }
    Volume::new(dims, [2.0, 1.0, 0.5], Samples::F32(v)).unwrap()
}

/// The field as glint computed it before bricks: every value and gradient of the
/// volume up front.
struct Oracle {
    dims: [usize; 3],
    values: Vec<f32>,
    gradients: Vec<[i16; 4]>,
    scale: f32,
    range: (f32, f32),
    cells: Vec<(f32, f32)>,
}

impl Oracle {
    fn new(volume: &Volume, prefilter: Prefilter) -> Oracle {
        let dims = volume.dims;
        let [nx, ny, nz] = dims;
        let mut values = volume.to_f32();
        let finite = values.iter().filter(|v| v.is_finite());
        let lo = finite.clone().fold(f32::INFINITY, |a, &b| a.min(b));
        let hi = finite.fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        for v in values.iter_mut().filter(|v| !v.is_finite()) {
            *v = lo;
        }
        if prefilter == Prefilter::Binomial {
            for axis in 0..3 {
                let src = values.clone();
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            let p = [i, j, k];
                            let (mut a, mut c) = (p, p);
                            a[axis] = p[axis].saturating_sub(1);
                            c[axis] = (p[axis] + 1).min(dims[axis] - 1);
                            let at = |q: [usize; 3]| src[q[0] + nx * (q[1] + ny * q[2])];
                            values[i + nx * (j + ny * k)] =
                                0.25 * at(a) + 0.5 * at(p) + 0.25 * at(c);
                        }
                    }
                }
            }
        }
        let to_index = inverse3(&linear_part(&volume.affine)).unwrap();
        let g = transpose3(&to_index).map(|r| r.map(|x| x as f32));
        let at = |i: usize, j: usize, k: usize| values[i + nx * (j + ny * k)];
        let world: Vec<[f32; 3]> = (0..nx * ny * nz)
            .map(|idx| {
                let (i, j, k) = (idx % nx, idx / nx % ny, idx / (nx * ny));
                let diff = |a: f32, b: f32, span: usize| (b - a) / span as f32;
                let (i0, i1) = (i.saturating_sub(1), (i + 1).min(nx - 1));
                let (j0, j1) = (j.saturating_sub(1), (j + 1).min(ny - 1));
                let (k0, k1) = (k.saturating_sub(1), (k + 1).min(nz - 1));
                let gi = diff(at(i0, j, k), at(i1, j, k), i1 - i0);
                let gj = diff(at(i, j0, k), at(i, j1, k), j1 - j0);
                let gk = diff(at(i, j, k0), at(i, j, k1), k1 - k0);
                [0, 1, 2].map(|r| g[r][0] * gi + g[r][1] * gj + g[r][2] * gk)
            })
            .collect();
        let largest = world.iter().flatten().fold(0.0f32, |m, x| m.max(x.abs()));
        let scale = if largest > 0.0 && largest.is_finite() {
            largest / 32767.0
        } else {
            1.0
        };
        let inv = 1.0 / scale;
        let q = |x: f32| {
            let y = x * inv;
            (y + 0.5f32.copysign(y)) as i16
        };
        let gradients = world
            .iter()
            .map(|w| [q(w[0]), q(w[1]), q(w[2]), 0])
            .collect();
        let cd = dims.map(|d| (d - 1).div_ceil(MACRO_CELL));
        let mut cells = Vec::new();
        for ck in 0..cd[2] {
            for cj in 0..cd[1] {
                for ci in 0..cd[0] {
                    let mut r = (f32::INFINITY, f32::NEG_INFINITY);
                    let span =
                        |c: usize, n: usize| c * MACRO_CELL..=((c + 1) * MACRO_CELL).min(n - 1);
                    for k in span(ck, nz) {
                        for j in span(cj, ny) {
                            for i in span(ci, nx) {
                                r = (r.0.min(at(i, j, k)), r.1.max(at(i, j, k)));
                            }
                        }
                    }
                    cells.push(r);
                }
            }
        }
        Oracle {
            dims,
            values,
            gradients,
            scale,
            range: (lo, hi),
            cells,
        }
    }

    /// The old `Field::value` and `Field::gradient` at `p`.
    fn sample(&self, p: Vec3) -> (f32, [f32; 3]) {
        let [nx, ny, nz] = self.dims;
        let c = |x: f32, n: usize| x.max(0.0).min((n - 2) as f32);
        let (fx, fy, fz) = (c(p.x, nx), c(p.y, ny), c(p.z, nz));
        let (i, j, k) = (fx as usize, fy as usize, fz as usize);
        let t = [
            (p.x - i as f32).clamp(0.0, 1.0),
            (p.y - j as f32).clamp(0.0, 1.0),
            (p.z - k as f32).clamp(0.0, 1.0),
        ];
        let base = i + nx * (j + ny * k);
        let (sy, sz) = (nx, nx * ny);
        let offs = [0, 1, sy, sy + 1, sz, sz + 1, sz + sy, sz + sy + 1];
        let tri = |v: [f32; 8]| {
            let x00 = v[0] + t[0] * (v[1] - v[0]);
            let x10 = v[2] + t[0] * (v[3] - v[2]);
            let x01 = v[4] + t[0] * (v[5] - v[4]);
            let x11 = v[6] + t[0] * (v[7] - v[6]);
            let y0 = x00 + t[1] * (x10 - x00);
            let y1 = x01 + t[1] * (x11 - x01);
            y0 + t[2] * (y1 - y0)
        };
        let value = tri(offs.map(|o| self.values[base + o]));
        let g = [0, 1, 2]
            .map(|a| tri(offs.map(|o| f32::from(self.gradients[base + o][a]))) * self.scale);
        (value, g)
    }
}

/// A field of `volume` against the oracle: range, robust range, macro cells, and the
/// value and gradient at every voxel and at scattered points, bit for bit.
fn check_against_oracle(volume: &Volume, prefilter: Prefilter) {
    let f = Field::with_prefilter(volume, prefilter).unwrap();
    let o = Oracle::new(volume, prefilter);
    assert_eq!(f.range(), o.range);
    assert_eq!(f.cells, o.cells);
    assert_eq!(f.gradient_scale.to_bits(), o.scale.to_bits());
    let robust = glint_io::robust_range(o.values.len(), |i| o.values[i] as f64)
        .map(|(a, b)| (a as f32, b as f32))
        .unwrap();
    assert_eq!(f.robust_range(), robust);
    assert_eq!(f.values(), &o.values[..]);
    let [nx, ny, nz] = volume.dims;
    let mut points: Vec<Vec3> = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                points.push(Vec3::new(i as f32, j as f32, k as f32));
            }
        }
    }
    // Scattered points, some outside the volume (clamped).
    let mut s = 12345u64;
    let mut rnd = |n: usize| {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) as f32 / (1u64 << 31) as f32 * (n as f32 + 2.0) - 1.0
    };
    for _ in 0..3000 {
        points.push(Vec3::new(rnd(nx), rnd(ny), rnd(nz)));
    }
    for p in points {
        let (v, g) = o.sample(p);
        assert_eq!(f.value(p).to_bits(), v.to_bits(), "value at {p:?}");
        let fg = f.gradient(p);
        assert_eq!(
            [fg.x, fg.y, fg.z].map(f32::to_bits),
            g.map(f32::to_bits),
            "gradient at {p:?}"
        );
    }
}

/// A smooth blob with noise on a grid of several bricks per axis, odd sizes (partial
/// bricks at the far faces).
fn blob(dims: [usize; 3]) -> Vec<i16> {
    let [nx, ny, nz] = dims;
    (0..nx * ny * nz)
        .map(|idx| {
            let (i, j, k) = (idx % nx, idx / nx % ny, idx / (nx * ny));
            let d =
                ((i as f32 - 20.0).powi(2) + (j as f32 - 9.0).powi(2) + (k as f32 - 17.0).powi(2))
                    .sqrt();
            (1000.0 - 40.0 * d) as i16 + (idx * 7919 % 13) as i16
        })
        .collect()
}

#[test]
fn bricks_equal_the_whole_volume_computation() {
    let dims = [37, 19, 34];
    for &prefilter in Prefilter::ALL {
        let mut vol = Volume::new(dims, [0.9, 1.1, 1.3], Samples::I16(blob(dims))).unwrap();
        // A sheared affine with an origin, and a rescale.
        vol.affine[0][1] = 0.2;
        vol.affine[2][0] = -0.15;
        vol.affine[1][3] = -40.0;
        vol.slope = 0.5;
        vol.intercept = -1024.0;
        check_against_oracle(&vol, prefilter);
    }
}

#[test]
fn nan_samples_and_small_volumes_equal_the_whole_volume_computation() {
    let dims = [18, 3, 17];
    let mut v: Vec<f32> = blob(dims).iter().map(|&x| f32::from(x) * 0.01).collect();
    v[5] = f32::NAN;
    v[700] = f32::INFINITY;
    let vol = Volume::new(dims, [1.0; 3], Samples::F32(v)).unwrap();
    for &prefilter in Prefilter::ALL {
        check_against_oracle(&vol, prefilter);
    }
    let tiny = Volume::new(
        [2, 2, 2],
        [1.0; 3],
        Samples::U8(vec![0, 10, 20, 30, 40, 50, 60, 70]),
    )
    .unwrap();
    check_against_oracle(&tiny, Prefilter::Binomial);
    check_against_oracle(&linear_volume(), Prefilter::None);
}

/// A float volume without NaN or infinities is read in one pass (the range measured
/// in it); one with a non-finite value in its last slab of slices passes again, after
/// a pass for its finite range, and equals the whole-volume computation.
#[test]
fn only_volumes_with_non_finite_values_take_a_range_pass() {
    // 80 slices of a small size: three slabs of up to 32 slices.
    let dims = [6, 5, 80];
    let values = |n: usize| (0..n).map(|i| (i * 37 % 101) as f32 * 0.5 - 7.0);
    let clean = Volume::new(dims, [1.0; 3], Samples::F32(values(480 * 5).collect())).unwrap();
    let field = Field::new(&clean).unwrap();
    let stages: Vec<&str> = field.timings().stages().iter().map(|s| s.0).collect();
    assert_eq!(stages, ["field: prepare"]);
    assert_eq!(field.range(), (-7.0, 43.0));
    check_against_oracle(&clean, Prefilter::Binomial);
    for bad in [f32::NAN, f32::NEG_INFINITY, f32::INFINITY] {
        let mut v: Vec<f32> = values(480 * 5).collect();
        v[2390] = bad;
        let vol = Volume::new(dims, [1.0; 3], Samples::F32(v)).unwrap();
        let field = Field::new(&vol).unwrap();
        let stages: Vec<&str> = field.timings().stages().iter().map(|s| s.0).collect();
        assert_eq!(stages, ["field: prepare", "field: range"], "{bad}");
        assert_eq!(field.range(), (-7.0, 43.0), "{bad}");
        for &prefilter in Prefilter::ALL {
            check_against_oracle(&vol, prefilter);
        }
    }
}

/// An axis-aligned affine (anisotropic, one axis flipped) takes the pass's shortcut
/// for the largest gradient component; its quantisation step and gradients stay the
/// oracle's, also when differences overflow f32 (where the shortcut gives way).
#[test]
fn axis_aligned_affines_equal_the_whole_volume_computation() {
    let dims = [21, 18, 11];
    let mut vol = Volume::new(dims, [0.7, 1.3, 2.1], Samples::I16(blob(dims))).unwrap();
    vol.affine[1][1] = -1.3;
    vol.affine[1][3] = 30.0;
    for &prefilter in Prefilter::ALL {
        check_against_oracle(&vol, prefilter);
    }
    let mut v: Vec<f32> = blob(dims).iter().map(|&x| f32::from(x)).collect();
    v[400] = 3e38;
    v[402] = -3e38;
    let mut huge = Volume::new(dims, [0.5, 1.0, 2.0], Samples::F32(v)).unwrap();
    huge.affine[0][0] = -0.5;
    check_against_oracle(&huge, Prefilter::None);
}

/// A pool far smaller than the bricks a pass reads: bricks are evicted and rebuilt,
/// or built outside the cache when it is full of bricks in use, with the same values.
#[test]
fn a_small_cache_evicts_and_rebuilds_the_same_bricks() {
    let dims = [70, 40, 50];
    let vol = Volume::new(dims, [1.0; 3], Samples::I16(blob(dims))).unwrap();
    let reference = Field::with_prefilter(&vol, Prefilter::Binomial).unwrap();
    let f = Field::with_prefilter(&vol, Prefilter::Binomial).unwrap();
    let small = Field {
        cache: BrickCache::new(f.brick_dims.iter().product(), 3).unwrap(),
        ..f
    };
    let points: Vec<Vec3> = (0..4000)
        .map(|n| {
            Vec3::new(
                (n * 37 % 69) as f32 + 0.3,
                (n * 11 % 39) as f32 + 0.6,
                (n * 7 % 49) as f32 + 0.1,
            )
        })
        .collect();
    // Twice over, so the second pass finds evicted bricks.
    for _ in 0..2 {
        let guard = crossbeam_epoch::pin();
        for &p in &points {
            assert_eq!(
                small.value_in(p, &guard).to_bits(),
                reference.value(p).to_bits()
            );
            assert_eq!(small.gradient_in(p, &guard), reference.gradient(p));
        }
        drop(guard);
        small.make_room();
    }
    let (built, evicted) = small.brick_counts();
    assert!(built > 2 && evicted > 0, "built {built}, evicted {evicted}");
    assert!(small.cache.used() <= 2);
}

#[test]
fn the_memory_limit_bounds_the_pool_and_refuses_what_cannot_fit() {
    // A limit too small for even the process: one clear error naming it.
    let (r, slots) = budget::reserve(0, 0, 10).unwrap();
    assert_eq!(slots, 11);
    drop(r);
    // Without a limit set, the pool of a volume of many bricks takes half the bytes of
    // its fixed data, or the least for a smaller one; one whose bricks all fit in the
    // floor gets them all.
    let brick = super::brick::BRICK_BYTES;
    let (_r, slots) = budget::reserve(1 << 30, 0, 1 << 20).unwrap();
    assert_eq!(u64::from(slots), (1 << 29) / brick);
    let (_r, slots) = budget::reserve(1 << 20, 0, 1 << 20).unwrap();
    assert_eq!(u64::from(slots), budget::DEFAULT_POOL_LEAST / brick);
    let all = budget::DEFAULT_POOL_FLOOR / brick - 1;
    let (_r, slots) = budget::reserve(1 << 20, 0, all as usize - 1).unwrap();
    assert_eq!(u64::from(slots), all);
    let err = budget::reserve(u64::MAX / 2, 0, 10)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("memory limit"), "{err}");
    assert!(err.contains("--memory-limit"), "{err}");
    // The first pass's buffers count against the limit (a pass that cannot fit is
    // refused, naming them) but do not enlarge the default pool.
    let (_r, slots) = budget::reserve(1 << 30, 1 << 28, 1 << 20).unwrap();
    assert_eq!(u64::from(slots), (1 << 29) / brick);
    let err = budget::reserve(0, u64::MAX / 2, 10)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("first pass's buffers"), "{err}");
    assert!(err.contains("--memory-limit"), "{err}");
}

/// The binomial keeps linear functions away from the faces (its weights are
/// symmetric and sum to 1) and spreads an impulse as the outer product of
/// (1, 2, 1) / 4 along the three axes.
#[test]
fn binomial_prefilter_keeps_linear_fields_and_spreads_an_impulse() {
    let vol = linear_volume();
    let f = Field::with_prefilter(&vol, Prefilter::Binomial).unwrap();
    assert_eq!(f.prefilter(), Prefilter::Binomial);
    let [nx, ny, nz] = f.dims;
    for k in 1..nz - 1 {
        for j in 1..ny - 1 {
            for i in 1..nx - 1 {
                let want = (2 * i + 3 * j) as f32 - k as f32;
                assert_eq!(f.values()[i + nx * (j + ny * k)], want, "({i}, {j}, {k})");
            }
        }
    }
    let mut v = vec![0.0f32; 125];
    v[2 + 5 * (2 + 5 * 2)] = 64.0;
    let impulse = Volume::new([5; 3], [1.0; 3], Samples::F32(v)).unwrap();
    let f = Field::with_prefilter(&impulse, Prefilter::Binomial).unwrap();
    let w = [0.0, 1.0, 2.0, 1.0, 0.0];
    for k in 0..5 {
        for j in 0..5 {
            for i in 0..5 {
                let want = w[i] * w[j] * w[k];
                assert_eq!(f.values()[i + 5 * (j + 5 * k)], want, "({i}, {j}, {k})");
            }
        }
    }
    assert_eq!(Field::new(&impulse).unwrap().prefilter(), Prefilter::None);
    assert_eq!(
        "binomial".parse::<Prefilter>().unwrap(),
        Prefilter::Binomial
    );
    assert!("gauss".parse::<Prefilter>().is_err());
}

#[test]
fn trilinear_reproduces_a_linear_field() {
    let f = Field::new(&linear_volume()).unwrap();
    let p = Vec3::new(1.25, 2.5, 3.75);
    let expect = 2.0 * 1.25 + 3.0 * 2.5 - 3.75;
    assert!((f.value(p) - expect).abs() < 1e-5);
}

#[test]
fn gradient_is_in_world_units() {
    // df/dx_world = (df/di) / spacing_x: 2/2, 3/1, -1/0.5.
    let f = Field::new(&linear_volume()).unwrap();
    let g = f.gradient(Vec3::new(0.3, 4.0, 5.0));
    // Stored in 16 bits: within half a step of the largest component's 1/32767.
    let tol = 0.5 * 3.0 / 32767.0 + 1e-6;
    assert!((g.x - 1.0).abs() < tol, "{g:?}");
    assert!((g.y - 3.0).abs() < tol, "{g:?}");
    assert!((g.z + 2.0).abs() < tol, "{g:?}");
}

#[test]
fn macro_cells_bound_the_values() {
    let f = Field::new(&linear_volume()).unwrap();
    // 4x5x6 voxels: cells cover voxels 0..=4 along each axis, then 4..=5 along z.
    assert_eq!(f.cell_dims, [1, 1, 2]);
    assert_eq!(f.cells[0], (-4.0, 6.0 + 12.0));
    assert_eq!(f.cells[1], (-5.0, 6.0 + 12.0 - 4.0));
}

#[test]
fn degenerate_volumes_are_rejected() {
    let flat = Volume::new([4, 4, 1], [1.0; 3], Samples::U8(vec![0; 16])).unwrap();
    assert!(matches!(Field::new(&flat), Err(RenderError::Volume(_))));
    let mut singular = linear_volume();
    singular.affine[2][2] = 0.0;
    assert!(Field::new(&singular).is_err());
    let nan = Volume::new([2, 2, 2], [1.0; 3], Samples::F32(vec![f32::NAN; 8])).unwrap();
    assert!(Field::new(&nan).is_err());
}

#[test]
fn robust_range_ignores_outlier_voxels() {
    // 4096 voxels 0..=4095, one replaced by -1.5e37 (the corrupt voxel):
    // the 0.5th and 99.5th percentiles of 4096 values are ranks 20 and 4075 (of
    // 0..=4095), i.e. the values 20 and 4075 once the outlier takes rank 0 from
    // the value 0 it replaced.
    let mut v: Vec<f32> = (0..4096).map(|i| i as f32).collect();
    v[0] = -1.5e37;
    let vol = Volume::new([16, 16, 16], [1.0; 3], Samples::F32(v)).unwrap();
    let f = Field::new(&vol).unwrap();
    assert_eq!(f.range(), (-1.5e37, 4095.0));
    assert_eq!(f.robust_range(), (20.0, 4075.0));
}

/// A frame rendered with a brick cache far too small for it (tiles that cannot get a
/// brick fall back to the reference loop and its spare bricks) is the frame rendered
/// with room for every brick, bit for bit, in both samplings.
#[test]
fn a_frame_under_memory_pressure_is_the_same_frame() {
    use crate::{Classification, ClassifySettings, FrameSettings, Sampling, TransferFunction};
    use glint_core::{Light, Material, Shader};
    use glint_lobe::{Geometry, LobeKind};
    let dims = [70, 40, 50];
    let vol = Volume::new(dims, [1.0; 3], Samples::I16(blob(dims))).unwrap();
    let roomy = Arc::new(Field::with_prefilter(&vol, Prefilter::Binomial).unwrap());
    let f = Field::with_prefilter(&vol, Prefilter::Binomial).unwrap();
    let tight = Arc::new(Field {
        cache: BrickCache::new(f.brick_dims.iter().product(), 4).unwrap(),
        ..f
    });
    let tf =
        TransferFunction::from_flat(&[0.0, 0.0, 400.0, 0.02, 1000.0, 0.3], &[0.0, 0.9, 0.7, 0.5])
            .unwrap();
    let shader = Shader::new(
        LobeKind::EnergyFit,
        20.0,
        4,
        Geometry::Phong,
        Material::default(),
        vec![Light::HEADLIGHT],
        0.0,
    )
    .unwrap();
    let frame = FrameSettings {
        width: 64,
        height: 48,
        ..Default::default()
    };
    for sampling in [Sampling::Point, Sampling::PreIntegrated] {
        let settings = ClassifySettings {
            sampling,
            ..Default::default()
        };
        let render = |field: &Arc<Field>| {
            Classification::new(field.clone(), &tf, &settings)
                .unwrap()
                .frame(&shader, &frame, None, crate::Transport::Local, &|_| {})
                .unwrap()
        };
        let (a, b) = (render(&roomy), render(&tight));
        assert!(a.alpha.iter().any(|&x| x > 0.5), "the blob is visible");
        assert_eq!(a.rgb, b.rgb, "{sampling:?}");
        assert_eq!(a.alpha, b.alpha, "{sampling:?}");
    }
    assert!(tight.brick_counts().1 > 0, "the tight cache evicted bricks");
}

/// A volume of `dims` (spacing 2, 1, 0.5 mm) with the values `f(i, j, k)`.
fn volume_of(dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f32) -> Volume {
    let mut v = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                v.push(f(i, j, k));
            }
        }
    }
    Volume::new(dims, [2.0, 1.0, 0.5], Samples::F32(v)).unwrap()
}

/// Sample points spread over `dims` (index units), many near brick faces (16, 32),
/// inside `margin` of the volume's faces.
fn spread(dims: [usize; 3], margin: f32) -> Vec<Vec3> {
    let mut out = Vec::new();
    for n in 0..400u32 {
        let r = |a: u32| {
            ((n.wrapping_mul(2654435761).wrapping_add(a * 40503)) % 10007) as f32 / 10007.0
        };
        let at = |a: usize, u: f32| margin + u * (dims[a] as f32 - 1.0 - 2.0 * margin);
        out.push(Vec3::new(at(0, r(1)), at(1, r(2)), at(2, r(3))));
    }
    for x in [15.0, 15.5, 16.0, 16.25, 16.99, 17.0, 31.7, 32.0] {
        out.push(Vec3::new(x, x.min(dims[1] as f32 - 1.0 - margin), 2.5));
    }
    out
}

/// The cubic B-spline of the raw samples with clamp-to-edge, tap by tap (the oracle).
fn spline_oracle(v: &Volume, p: Vec3) -> f32 {
    let w = |t: f64| {
        let s = 1.0 - t;
        [
            s * s * s / 6.0,
            (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
            t * t * t / 6.0,
        ]
    };
    let p = [p.x, p.y, p.z].map(f64::from);
    let i = [0, 1, 2].map(|a| (p[a].floor() as isize).min(v.dims[a] as isize - 2));
    let ws = [0, 1, 2].map(|a| w(p[a] - i[a] as f64));
    let mut sum = 0.0;
    for c in 0..4 {
        for b in 0..4 {
            for a in 0..4 {
                let at = |x: usize, o: usize| {
                    (i[x] + o as isize - 1).clamp(0, v.dims[x] as isize - 1) as usize
                };
                sum += ws[0][a] * ws[1][b] * ws[2][c] * v.value(at(0, a), at(1, b), at(2, c));
            }
        }
    }
    sum as f32
}

#[test]
fn tricubic_reproduces_a_linear_field_and_its_constant_gradient() {
    // 40x36x20 voxels: bricks of 16 cells, so samples read one brick, or span two
    // or more (the eight-fetch path).
    let dims = [40, 36, 20];
    let volume = volume_of(dims, |i, j, k| (2 * i + 3 * j) as f32 - k as f32);
    let f = Field::new(&volume).unwrap().with_filter(Filter::Tricubic);
    assert_eq!(f.filter(), Filter::Tricubic);
    // Away from the faces (where clamping the taps bends the line).
    for p in spread(dims, 1.0) {
        let want = 2.0 * p.x + 3.0 * p.y - p.z;
        assert!(
            (f.value(p) - want).abs() < 2e-4,
            "{p:?}: {} vs {want}",
            f.value(p)
        );
        // World gradient: (2/2, 3/1, -1/0.5).
        let g = f.gradient(p);
        let err = (g.x - 1.0)
            .abs()
            .max((g.y - 3.0).abs())
            .max((g.z + 2.0).abs());
        assert!(err < 1e-4, "{p:?}: {g:?}");
    }
}

#[test]
fn tricubic_of_a_constant_field_is_constant_everywhere() {
    let dims = [20, 18, 34];
    let f = Field::new(&volume_of(dims, |_, _, _| 7.5))
        .unwrap()
        .with_filter(Filter::Tricubic);
    for p in spread(dims, 0.0) {
        assert!((f.value(p) - 7.5).abs() < 1e-5, "{p:?}: {}", f.value(p));
        let g = f.gradient(p);
        assert!(
            g.x.abs().max(g.y.abs()).max(g.z.abs()) < 1e-5,
            "{p:?}: {g:?}"
        );
    }
}

/// On a rough field: the tap-by-tap spline (both evaluations: within a brick and by
/// eight fetches across bricks), within the (min, max) of its 4^3 taps, and within
/// the dilated macro cell's range that light transport bounds it by.
#[test]
fn tricubic_is_the_spline_within_its_taps_and_its_macro_cell() {
    let dims = [37, 21, 19];
    let rough = |i: usize, j: usize, k: usize| {
        (((i * 7919 + j * 104729 + k * 1299709) % 1013) as f32).sqrt() - 10.0
    };
    let volume = volume_of(dims, rough);
    let f = Field::new(&volume).unwrap().with_filter(Filter::Tricubic);
    let guard = crossbeam_epoch::pin();
    for p in spread(dims, 0.0) {
        let loc = f.locate(p);
        let v = f.value_at(&loc, &guard);
        let want = spline_oracle(&volume, p);
        assert!((v - want).abs() < 1e-4, "{p:?}: {v} vs {want}");
        // The eight fetches agree with the 64 taps wherever those apply.
        assert!(
            (f.fetched(&loc, &guard, [false; 3]) - v).abs() < 1e-4,
            "{p:?}"
        );
        let mut taps = (f32::INFINITY, f32::NEG_INFINITY);
        for c in 0..4 {
            for b in 0..4 {
                for a in 0..4 {
                    let at =
                        |x: usize, o: usize| (loc.ijk[x] + o).saturating_sub(1).min(dims[x] - 1);
                    let t = volume.value(at(0, a), at(1, b), at(2, c)) as f32;
                    taps = (taps.0.min(t), taps.1.max(t));
                }
            }
        }
        assert!(
            v >= taps.0 - 1e-5 && v <= taps.1 + 1e-5,
            "{p:?}: {v} outside {taps:?}"
        );
        let cell = f.macro_cells().1[f.cell_index(&loc)];
        assert!(
            v >= cell.0 - 1e-5 && v <= cell.1 + 1e-5,
            "{p:?}: {v} outside cell {cell:?}"
        );
    }
}

/// The tricubic macro cells reach one voxel beyond the trilinear cells, no more: an
/// impulse lights up only the cells whose samples read it.
#[test]
fn tricubic_macro_cells_reach_one_voxel_beyond_their_cells() {
    let dims = [30, 26, 22];
    let at = [10, 12, 5];
    let volume = volume_of(dims, |i, j, k| f32::from([i, j, k] == at));
    let f = Field::with_prefilter(&volume, Prefilter::None)
        .unwrap()
        .with_filter(Filter::Tricubic);
    let (cd, cells) = f.macro_cells();
    for (n, &(lo, hi)) in cells.iter().enumerate() {
        let c = [n % cd[0], n / cd[0] % cd[1], n / (cd[0] * cd[1])];
        // Samples in cell c read voxels 4c - 1 ..= 4c + 5 per axis.
        let reads =
            (0..3).all(|a| at[a] + 1 >= MACRO_CELL * c[a] && at[a] <= MACRO_CELL * c[a] + 5);
        assert_eq!(lo, 0.0, "{c:?}");
        assert_eq!(hi, f32::from(reads), "{c:?}");
    }
}

/// Trilinear stays the default, bit for bit, and a field set to tricubic and back is
/// the trilinear field again (values, gradients, macro cells).
#[test]
fn trilinear_is_the_default_bit_for_bit() {
    let dims = [37, 21, 19];
    let volume = volume_of(dims, |i, j, k| ((i * 31 + j * 17 + k * 7) % 23) as f32);
    let plain = Field::new(&volume).unwrap();
    assert_eq!(plain.filter(), Filter::Trilinear);
    assert_eq!(Filter::default(), Filter::Trilinear);
    let back = Field::new(&volume)
        .unwrap()
        .with_filter(Filter::Tricubic)
        .with_filter(Filter::Trilinear);
    assert_eq!(back.cells, plain.cells);
    for p in spread(dims, 0.0) {
        assert_eq!(back.value(p).to_bits(), plain.value(p).to_bits(), "{p:?}");
        assert_eq!(back.gradient(p), plain.gradient(p), "{p:?}");
    }
    assert_eq!("Tricubic".parse::<Filter>().unwrap(), Filter::Tricubic);
    assert!("catmull".parse::<Filter>().is_err());
}
