//! The batch kernels against `Lobe::eval`, on every path the CPU has (issue 34).
use super::*;

/// Distance in representable f32 values; +0 and -0 are the same point.
fn ulp_diff(a: f32, b: f32) -> u64 {
    if a.is_nan() || b.is_nan() {
        return if a.is_nan() && b.is_nan() {
            0
        } else {
            u64::MAX
        };
    }
    let key = |x: f32| {
        let i = x.to_bits() as i32;
        i64::from(if i < 0 { i32::MIN - i } else { i })
    };
    (key(a) - key(b)).unsigned_abs()
}

#[test]
fn ulp_diff_counts_steps() {
    assert_eq!(ulp_diff(1.0, 1.0), 0);
    assert_eq!(ulp_diff(1.0, f32::from_bits(1.0f32.to_bits() + 2)), 2);
    assert_eq!(ulp_diff(0.0, -0.0), 0);
    assert_eq!(ulp_diff(f32::from_bits(1), -f32::from_bits(1)), 2);
}

/// Inputs that exercise every branch: specials, the clamp region, subnormals,
/// values near 1 (where the lobes live), a dense sweep, and scattered bit patterns.
fn inputs() -> Vec<f32> {
    let mut v = vec![
        f32::NAN,
        -f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        1.0,
        -1.0,
        2.0,
        -2.0,
        1e30,
        -1e30,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::from_bits(0x007f_ffff),
        -f32::from_bits(1),
        0.5,
        0.7,
        0.69921875,
        0.98046875,
        1.0234375,
    ];
    // Every f32 just below 1.
    v.extend((1..2000u32).map(|i| f32::from_bits(1.0f32.to_bits() - i)));
    // A dense sweep over [-1.1, 1.1].
    v.extend((0..20_000).map(|i| -1.1 + 2.2 * i as f32 / 20_000.0));
    // Angles up to 90 degrees.
    v.extend((0..5_000).map(|i| (i as f32 * 90.0 / 5_000.0).to_radians().cos()));
    // Scattered bit patterns (all classes, including NaN payloads), xorshift.
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    v.extend((0..5_000).map(|_| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        f32::from_bits(s as u32)
    }));
    // An odd length, so the vector loops' remainders run too.
    v.push(0.25);
    v
}

fn lobes() -> Vec<Lobe<f32>> {
    let mut lobes = Vec::new();
    for &kind in LobeKind::ALL {
        for &n in &[0.0, 0.5, 1.0, 7.0, 16.0, 100.0, 1000.0, 10_000.0] {
            let vs: &[u32] = if kind.uses_v() { &[0, 1, 4, 10] } else { &[4] };
            for &v in vs {
                if kind == LobeKind::Minimax && !(v == 4 && (n == 100.0 || n == 7.0)) {
                    continue; // minimax's search is slow in the dev profile
                }
                lobes.push(Lobe::new(kind, n, v).unwrap());
            }
        }
    }
    lobes
}

/// Max ulp distance allowed between a path and `Lobe::eval`.
fn tolerance(kind: LobeKind) -> u64 {
    match kind {
        // Different (both ≤ 1 ulp) implementations of pow/exp.
        LobeKind::Exact | LobeKind::Gauss => 2,
        // The same IEEE operations in the same order.
        _ => 0,
    }
}

thread_local! {
    /// Calls of each path's kernel on this thread (`run_aligned`).
    static RUNS: std::cell::Cell<[u64; 3]> = const { std::cell::Cell::new([0; 3]) };
}

/// Counts one call of `path`'s kernel (called by `run_aligned` in test builds).
pub(super) fn count_run(path: KernelPath) {
    RUNS.with(|r| {
        let mut n = r.get();
        n[path as usize] += 1;
        r.set(n);
    });
}

/// Calls of `path`'s kernel on this thread so far.
fn runs(path: KernelPath) -> u64 {
    RUNS.with(|r| r.get()[path as usize])
}

/// The x86 flags the CPU announces in /proc/cpuinfo (Linux): an account of the CPU
/// independent of `is_x86_feature_detected!`.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
fn cpuinfo_flags() -> Option<Vec<String>> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("flags"))?;
    let (_, flags) = line.split_once(':')?;
    Some(flags.split_whitespace().map(str::to_string).collect())
}

/// The paths the CPU supports by /proc/cpuinfo match the dispatcher's detection,
/// so a detection bug cannot make the tests below skip a path the CPU has.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
#[test]
fn detection_agrees_with_proc_cpuinfo() {
    let Some(flags) = cpuinfo_flags() else {
        glint_testkit::missing("/proc/cpuinfo flags");
        return;
    };
    let has = |f: &str| flags.iter().any(|x| x == f);
    let avx2 = has("avx2") && has("fma");
    let avx512 = avx2 && ["avx512f", "avx512vl", "avx512dq", "avx512bw"].map(has) == [true; 4];
    assert_eq!(KernelPath::Avx2.is_supported(), avx2, "{flags:?}");
    assert_eq!(KernelPath::Avx512.is_supported(), avx512, "{flags:?}");
}

/// Every path the CPU supports runs its own kernel when asked (counted in
/// `run_aligned`), and the best path is the widest within the cap.
#[test]
fn every_supported_path_runs_its_kernel() {
    let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
    let cos = [0.99f32; 40];
    let mut out = [0.0f32; 40];
    for &path in KernelPath::ALL {
        let before = runs(path);
        let r = eval_slice_with(&k, path, &cos, &mut out);
        assert_eq!(r.is_ok(), path.is_supported(), "{path}");
        assert_eq!(runs(path) > before, path.is_supported(), "{path}");
    }
    // The dispatcher: Lobe::eval_slice takes the best path within GLINT_SIMD.
    let best = KernelPath::best();
    assert_eq!(best, KernelPath::best_within(KernelPath::cap()));
    let before = runs(best);
    k.eval_slice(&cos, &mut out);
    assert!(runs(best) > before, "eval_slice did not run {best}");
    eprintln!("lobe batch: best path {best} (cap {})", KernelPath::cap());
}

/// The override forces any narrower path, on any machine: a cap gives the widest
/// supported path no wider than it, and scalar always.
#[test]
fn a_cap_forces_a_narrower_path() {
    assert_eq!(
        KernelPath::best_within(KernelPath::Scalar),
        KernelPath::Scalar
    );
    for &cap in KernelPath::ALL {
        let got = KernelPath::best_within(cap);
        assert!(got <= cap && got.is_supported(), "{cap}: {got}");
        let want = KernelPath::supported()
            .into_iter()
            .filter(|&p| p <= cap)
            .max();
        assert_eq!(Some(got), want, "{cap}");
    }
    assert_eq!(KernelPath::parse_cap(None), Ok(KernelPath::Avx512));
    assert_eq!(KernelPath::parse_cap(Some("")), Ok(KernelPath::Avx512));
    assert_eq!(
        KernelPath::parse_cap(Some("Scalar")),
        Ok(KernelPath::Scalar)
    );
    assert_eq!(KernelPath::parse_cap(Some("avx2")), Ok(KernelPath::Avx2));
    assert_eq!(KernelPath::parse_cap(Some("sse")), Err("sse".to_string()));
    // Under scripts/test's GLINT_SIMD=scalar pass, the process really is capped (an
    // unknown value is ignored: no cap).
    let v = std::env::var("GLINT_SIMD").ok();
    let want = KernelPath::parse_cap(v.as_deref()).unwrap_or(KernelPath::Avx512);
    assert_eq!(KernelPath::cap(), want);
    assert!(KernelPath::best() <= KernelPath::cap());
}

fn check_path(path: KernelPath) {
    if !path.is_supported() {
        glint_testkit::skipped(&format!("lobe batch {path}"), "this CPU lacks it");
        return;
    }
    let cos = inputs();
    let mut out = vec![0.0f32; cos.len()];
    let mut reference = vec![0.0f32; cos.len()];
    let mut worst = 0;
    for lobe in lobes() {
        eval_slice_with(&lobe, path, &cos, &mut out).unwrap();
        eval_slice_with(&lobe, KernelPath::Scalar, &cos, &mut reference).unwrap();
        for ((&c, &y), &r) in cos.iter().zip(&out).zip(&reference) {
            let e = lobe.eval(c);
            let d = ulp_diff(y, e);
            assert!(
                d <= tolerance(lobe.kind()),
                "{path} {lobe:?} c = {c:e} ({:#x}): {y:e} vs eval {e:e} ({d} ulp)",
                c.to_bits()
            );
            if lobe.kind() == LobeKind::Exact || lobe.kind() == LobeKind::Gauss {
                worst = worst.max(d);
            }
            assert!((0.0..=1.0).contains(&y), "{path} {lobe:?} c = {c}: {y}");
            // Every path runs the same operations: bit-identical to the fallback.
            assert_eq!(
                y.to_bits(),
                r.to_bits(),
                "{path} vs scalar, {lobe:?} c = {c:e}"
            );
        }
    }
    println!(
        "batch path {path}: RAN ({} inputs x {} lobes; power fits and schlick \
         bit-identical to eval, exact/gauss at most {worst} ulp from eval)",
        cos.len(),
        lobes().len()
    );
    glint_testkit::ran(&format!("lobe batch {path}"));
}

#[test]
fn scalar_path_agrees_with_eval() {
    check_path(KernelPath::Scalar);
}

#[test]
fn avx2_path_agrees_with_eval() {
    check_path(KernelPath::Avx2);
}

#[test]
fn avx512_path_agrees_with_eval() {
    check_path(KernelPath::Avx512);
}

#[test]
fn every_alignment_and_length_gives_eval_values() {
    // Subslices at every offset and of lengths around the vector widths cover the
    // alignment peel, the vector loops and their remainders.
    let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
    let cos: Vec<f32> = (0..300).map(|i| 1.0 - i as f32 / 256.0).collect();
    let mut out = vec![0.0f32; 300];
    for path in KernelPath::supported() {
        for offset in 0..17 {
            for len in [
                0,
                1,
                15,
                16,
                17,
                31,
                32,
                33,
                63,
                64,
                65,
                100,
                200,
                283 - offset,
            ] {
                let src = &cos[offset..offset + len];
                let dst = &mut out[offset..offset + len];
                dst.fill(f32::NAN);
                eval_slice_with(&k, path, src, dst).unwrap();
                for (&c, &y) in src.iter().zip(dst.iter()) {
                    assert_eq!(y.to_bits(), k.eval(c).to_bits(), "{path} {offset} {len}");
                }
            }
        }
    }
}

#[test]
fn unsupported_path_and_length_mismatch_are_errors() {
    let k = Lobe::<f32>::new(LobeKind::EnergyFit, 100.0, 4).unwrap();
    let mut out = [0.0; 2];
    assert_eq!(
        eval_slice_with(&k, KernelPath::Scalar, &[1.0], &mut out),
        Err(BatchError::LengthMismatch {
            input: 1,
            output: 2
        })
    );
    for &path in KernelPath::ALL {
        let r = eval_slice_with(&k, path, &[1.0, 0.0], &mut out);
        assert_eq!(r.is_ok(), path.is_supported());
    }
}

/// `c^n` correctly rounded to f32, from f64 `powf` (glibc's pow is < 1 ulp in
/// f64, far below the f32 rounding step).
fn pow_reference(c: f32, n: f32) -> f32 {
    f64::from(c).powf(f64::from(n)) as f32
}

/// The stated accuracy of the vectorised pow: at most 1 ulp from the correctly
/// rounded `c^n`, on every path, over normal and subnormal `c` and results.
#[test]
fn vectorised_pow_is_within_one_ulp() {
    let mut cos: Vec<f32> = Vec::new();
    // Every 4099th f32 in (0, 1]: all binades, subnormals included.
    let mut bits = 1u32;
    while bits <= 1.0f32.to_bits() {
        cos.push(f32::from_bits(bits));
        bits += 4099;
    }
    cos.extend((1..4000u32).map(|i| f32::from_bits(1.0f32.to_bits() - i)));
    let mut out = vec![0.0; cos.len()];
    let ns = [
        0.0, 1e-3, 0.37, 0.5, 1.0, 2.0, 3.7, 16.0, 63.5, 100.0, 1000.0, 4321.5, 10_000.0,
    ];
    let mut paths_run = Vec::new();
    for path in KernelPath::supported() {
        paths_run.push(path.name());
        let (mut worst, mut exact_count, mut total) = (0, 0usize, 0usize);
        for &n in &ns {
            let lobe = Lobe::<f32>::new(LobeKind::Exact, f64::from(n), 4).unwrap();
            eval_slice_with(&lobe, path, &cos, &mut out).unwrap();
            for (&c, &y) in cos.iter().zip(&out) {
                let d = ulp_diff(y, pow_reference(c, n));
                assert!(d <= 1, "{path}: {c:e}^{n} = {y:e}, f64 pow says {:e}", {
                    pow_reference(c, n)
                });
                worst = worst.max(d);
                exact_count += usize::from(d == 0);
                total += 1;
            }
        }
        println!(
            "vectorised pow on {path}: max {worst} ulp, {:.4}% correctly rounded of {total}",
            100.0 * exact_count as f64 / total as f64
        );
    }
    println!("vectorised pow accuracy: ran paths {paths_run:?}");
}

/// The gauss kernel's exp against f64 exp, same bound.
#[test]
fn vectorised_exp_is_within_one_ulp() {
    for path in KernelPath::supported() {
        for &n in &[0.5f32, 10.0, 100.0, 1000.0, 10_000.0] {
            let lobe = Lobe::<f32>::new(LobeKind::Gauss, f64::from(n), 4).unwrap();
            let cos: Vec<f32> = (0..=20_000).map(|i| i as f32 / 20_000.0).collect();
            let mut out = vec![0.0; cos.len()];
            eval_slice_with(&lobe, path, &cos, &mut out).unwrap();
            for (&c, &y) in cos.iter().zip(&out) {
                let t = n * (c - 1.0); // the f32 argument, as eval forms it
                let r = f64::from(t).exp() as f32;
                assert!(ulp_diff(y, r) <= 1, "{path}: exp({t}) = {y:e} vs {r:e}");
            }
        }
        println!("vectorised exp: ran path {path}");
    }
}

#[test]
fn tables_match_their_definitions() {
    // Independent of mpmath: f64 libm exp2/log2 agree to a few f64 ulp.
    for (i, &t) in EXP2_TABLE.iter().enumerate() {
        let v = f64::from_bits(t.wrapping_add((i as u64) << 48));
        assert!(
            (v - (i as f64 / 16.0).exp2()).abs() <= 4.0 * f64::EPSILON,
            "{i}"
        );
    }
    for i in 0..16 {
        assert!((LOG2_LOGC[i] + LOG2_INVC[i].log2()).abs() <= 4.0 * f64::EPSILON);
        // 1/invc lies inside subinterval i.
        let lo = f64::from(f32::from_bits(LOG2_OFF + ((i as u32) << 19)));
        let hi = f64::from(f32::from_bits(LOG2_OFF + ((i as u32 + 1) << 19)));
        let c = 1.0 / LOG2_INVC[i];
        assert!(lo <= c && c <= hi, "{i}: {lo} {c} {hi}");
    }
}
