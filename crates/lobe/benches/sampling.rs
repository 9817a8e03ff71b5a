//! Sampling cost per sample of every lobe against sampling `cos^n`, in one run.
//!
//! `cargo bench -p glint-lobe --bench sampling`
//!
//! Divan times `sample(u1, u2)` (axis frame: the inverse CDF and the azimuth's
//! `sin_cos`), `pdf` at the sampled directions, and a Blinn world-space draw
//! (`Scatter::sample`: frame, reflection, Jacobian) for each lobe in f32, over a block
//! of 4096 precomputed uniform pairs (PCG64-MCG, seed 1). It then prints ns per sample
//! and the ratio to `exact` (sampling `cos^n`: one `powf`) from a second, shorter
//! measurement of every workload in this process (fastest of many ~1 ms runs).
//! n = 100, v = 4 (the paper's case); `k` also at n = 3 (`a < 1/2`: the support is
//! cut at `c = -1` and the sampler takes `ln_1p` + `exp_m1` instead of one `powf`).

use std::hint::black_box;
use std::time::{Duration, Instant};

use divan::counter::ItemsCount;
use divan::Bencher;
use glint_lobe::{AxisLobe, Geometry, Lobe, LobeKind, LobeSampler, Scatter};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const LEN: usize = 4096;
const N: f64 = 100.0;
const V: u32 = 4;

fn uniforms() -> Vec<(f32, f32)> {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    (0..LEN).map(|_| (rng.random(), rng.random())).collect()
}

fn sampler(kind: LobeKind, n: f64) -> LobeSampler<f32> {
    LobeSampler::new(&Lobe::new(kind, n, V).expect("valid parameters"))
}

/// What is timed, per sample.
#[derive(Clone, Copy)]
enum Op {
    /// `sample(u1, u2)` in the axis frame.
    Sample,
    /// `pdf` of an axis-frame direction.
    Pdf,
    /// A Blinn draw in world space (`Scatter::sample`).
    Blinn,
}

fn run(s: &LobeSampler<f32>, op: Op, us: &[(f32, f32)], dirs: &[[f32; 3]], out: &mut [f32]) {
    match op {
        Op::Sample => {
            for (o, &(u1, u2)) in out.iter_mut().zip(us) {
                let d = s.sample(u1, u2);
                *o = d[0] + d[1] + d[2];
            }
        }
        Op::Pdf => {
            for (o, &d) in out.iter_mut().zip(dirs) {
                *o = s.pdf(d);
            }
        }
        Op::Blinn => {
            let sc = Scatter::new(Geometry::Blinn, [0.0, 0.0, 1.0], [0.6, 0.0, 0.8])
                .expect("unit vectors");
            for (o, &(u1, u2)) in out.iter_mut().zip(us) {
                *o = sc.sample(s, u1, u2).map_or(0.0, |x| x.pdf);
            }
        }
    }
}

fn bench(bencher: Bencher, kind: LobeKind, n: f64, op: Op) {
    let s = sampler(kind, n);
    let us = uniforms();
    let dirs: Vec<[f32; 3]> = us.iter().map(|&(a, b)| s.sample(a, b)).collect();
    let mut out = vec![0.0f32; LEN];
    bencher.counter(ItemsCount::new(LEN)).bench_local(|| {
        run(
            black_box(&s),
            op,
            black_box(&us),
            black_box(&dirs),
            &mut out,
        )
    });
}

#[divan::bench(args = LobeKind::ALL)]
fn sample(bencher: Bencher, kind: LobeKind) {
    bench(bencher, kind, N, Op::Sample);
}

#[divan::bench(args = LobeKind::ALL)]
fn pdf(bencher: Bencher, kind: LobeKind) {
    bench(bencher, kind, N, Op::Pdf);
}

#[divan::bench(args = LobeKind::ALL)]
fn blinn_world(bencher: Bencher, kind: LobeKind) {
    bench(bencher, kind, N, Op::Blinn);
}

#[divan::bench]
fn sample_k_cut_support(bencher: Bencher) {
    bench(bencher, LobeKind::EnergyFit, 3.0, Op::Sample);
}

/// ns per sample, fastest of ~1 ms runs over `budget`.
fn ns_per_sample(s: &LobeSampler<f32>, op: Op, budget: Duration) -> f64 {
    let us = uniforms();
    let dirs: Vec<[f32; 3]> = us.iter().map(|&(a, b)| s.sample(a, b)).collect();
    let mut out = vec![0.0f32; LEN];
    let start = Instant::now();
    let mut best = f64::INFINITY;
    while start.elapsed() < budget {
        let t = Instant::now();
        for _ in 0..4 {
            run(black_box(s), op, black_box(&us), black_box(&dirs), &mut out);
        }
        best = best.min(t.elapsed().as_secs_f64() * 1e9 / (4 * LEN) as f64);
    }
    black_box(&out);
    best
}

fn main() {
    divan::main();
    let budget = Duration::from_millis(300);
    let mut rows: Vec<(String, LobeSampler<f32>)> = LobeKind::ALL
        .iter()
        .map(|&k| (format!("{k} n={N}"), sampler(k, N)))
        .collect();
    rows.push((
        "k n=3 (cut support)".into(),
        sampler(LobeKind::EnergyFit, 3.0),
    ));
    println!();
    println!("ns per sample (f32, v = {V}, single thread; ratio to exact = sampling cos^n):");
    println!(
        "{:>22} {:>9} {:>8} {:>9} {:>8} {:>9} {:>8}",
        "lobe", "sample", "x exact", "pdf", "x exact", "blinn", "x exact"
    );
    let ops = [Op::Sample, Op::Pdf, Op::Blinn];
    let reference: Vec<f64> = ops
        .iter()
        .map(|&op| ns_per_sample(&rows[0].1, op, budget))
        .collect();
    for (name, s) in &rows {
        let t: Vec<f64> = ops.iter().map(|&op| ns_per_sample(s, op, budget)).collect();
        println!(
            "{name:>22} {:>9.2} {:>8.2} {:>9.2} {:>8.2} {:>9.2} {:>8.2}",
            t[0],
            t[0] / reference[0],
            t[1],
            t[1] / reference[1],
            t[2],
            t[2] / reference[2]
        );
    }
}
