//! Lobe throughput against libm powf and a plain copy, in one run.
//!
//! `cargo bench -p glint-lobe --bench lobes`
//!
//! Divan times every lobe's batch kernel (`Lobe::<f32>::eval_slice`, dispatched to
//! the widest SIMD path), the scalar `eval` loop for `k`, libm `powf` (cos^n, the
//! reference) and `copy_from_slice` of the same bytes (the bandwidth bound), over an
//! L1-resident block of 4096 f32 (16 KiB in + 16 KiB out) and over 1M-element arrays
//! (4 MiB + 4 MiB, beyond L2). It then prints a ratio table from a second, shorter
//! measurement of the same workloads (`glint_lobe::measure`), so the ratios come
//! from one process on one data set. n = 100, v = 4 throughout (the paper's case).

use std::hint::black_box;
use std::time::Duration;

use divan::counter::ItemsCount;
use divan::Bencher;
use glint_lobe::measure::{cosines, measure, Workload};
use glint_lobe::{KernelPath, Lobe, LobeKind};

/// The L1-resident block and the 1M array.
const LENS: [usize; 2] = [4096, 1 << 20];
const N: f64 = 100.0;
const V: u32 = 4;

fn lobe(kind: LobeKind) -> Lobe<f32> {
    Lobe::new(kind, N, V).expect("valid parameters")
}

fn bench_workload(bencher: Bencher, len: usize, workload: Workload) {
    let cos = cosines(len);
    let mut out = vec![0.0f32; len];
    bencher
        .counter(ItemsCount::new(len))
        .bench_local(|| workload.run(black_box(&cos), black_box(&mut out)));
}

#[divan::bench(args = LENS)]
fn copy(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Copy);
}

#[divan::bench(args = LENS)]
fn libm_powf(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::LibmPowf { n: N as f32 });
}

#[divan::bench(args = LENS)]
fn exact_vectorised_pow(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::Exact)));
}

#[divan::bench(args = LENS)]
fn k(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::EnergyFit)));
}

#[divan::bench(args = LENS)]
fn k_scalar_eval(bencher: Bencher, len: usize) {
    bench_workload(
        bencher,
        len,
        Workload::LobeScalar(lobe(LobeKind::EnergyFit)),
    );
}

#[divan::bench(args = LENS)]
fn g(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::SlopeFit)));
}

#[divan::bench(args = LENS)]
fn minimax(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::Minimax)));
}

#[divan::bench(args = LENS)]
fn schlick(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::Schlick)));
}

#[divan::bench(args = LENS)]
fn gauss(bencher: Bencher, len: usize) {
    bench_workload(bencher, len, Workload::Lobe(lobe(LobeKind::Gauss)));
}

fn main() {
    divan::main();
    ratio_table();
}

/// Ratios from one more measurement of every workload, in this process.
fn ratio_table() {
    let mut rows: Vec<(String, Workload)> = vec![
        ("copy (bandwidth bound)".into(), Workload::Copy),
        ("libm powf cos^n".into(), Workload::LibmPowf { n: N as f32 }),
        (
            "exact (vectorised pow)".into(),
            Workload::Lobe(lobe(LobeKind::Exact)),
        ),
        (
            "k, scalar eval loop".into(),
            Workload::LobeScalar(lobe(LobeKind::EnergyFit)),
        ),
    ];
    for kind in LobeKind::ALL
        .iter()
        .copied()
        .filter(|&k| k != LobeKind::Exact)
    {
        rows.push((kind.name().into(), Workload::Lobe(lobe(kind))));
    }
    for path in KernelPath::supported() {
        rows.push((
            format!("k, {path} path"),
            Workload::LobeOnPath(lobe(LobeKind::EnergyFit), path),
        ));
    }
    println!();
    println!(
        "Ratios (n = {N}, v = {V}, SIMD path {}, single thread, fastest ~{:?} sample):",
        KernelPath::best(),
        glint_lobe::measure::SAMPLE_TIME
    );
    for len in LENS {
        let cos = cosines(len);
        let rates: Vec<f64> = rows
            .iter()
            .map(|(_, w)| measure(w, &cos, Duration::from_millis(300)).evals_per_sec)
            .collect();
        let (copy, powf) = (rates[0], rates[1]);
        println!(
            "{:>24} {:>9} {:>12} {:>10} {:>9}",
            "workload", "len", "evals/s", "x powf", "x copy"
        );
        for ((name, _), rate) in rows.iter().zip(&rates) {
            println!(
                "{name:>24} {len:>9} {rate:>12.3e} {:>10.2} {:>9.3}",
                rate / powf,
                rate / copy
            );
        }
        println!();
    }
    subnormal_cost();
}

/// The cost of subnormal results: the kernels keep gradual underflow (as `eval`
/// does), and on Intel cores a vector instruction with a subnormal result takes a
/// microcode assist. Times `k` on the L1 block as is and with the few inputs whose
/// K_4 is subnormal (or underflows on the way) moved to c = 1.
fn subnormal_cost() {
    let k = lobe(LobeKind::EnergyFit);
    let cos = cosines(LENS[0]);
    let a = k.coefficient().expect("k is a power fit") as f32;
    // b = 1 - a(1 - c) below 2^(-126/16) = 0.0043 gives b^16 < 2^-126.
    let clean: Vec<f32> = cos
        .iter()
        .map(|&c| {
            let b = 1.0 - a * (1.0 - c);
            if b > 0.0 && b < 0.0044 {
                1.0
            } else {
                c
            }
        })
        .collect();
    let moved = cos.iter().zip(&clean).filter(|(x, y)| x != y).count();
    let budget = Duration::from_millis(300);
    let with = measure(&Workload::Lobe(k), &cos, budget).evals_per_sec;
    let without = measure(&Workload::Lobe(k), &clean, budget).evals_per_sec;
    println!(
        "Subnormal results: k on the {} inputs {with:.3e} evals/s; with the {moved} inputs \
         whose result is subnormal moved to c = 1: {without:.3e} ({:+.0}%)",
        LENS[0],
        100.0 * (without / with - 1.0)
    );
}
