//! Criterion bench: the MNI152 T1 template at 512x512, step 0.5 voxel, composite with
//! shading (mr-t2-brain preset), view from the left, with `--lobe exact`, `--lobe k` and
//! `--lobe hw` (the default unit's table).
//!
//! The template comes from scripts/fetch-samples (path in `GLINT_MNI152`, default
//! `~/.cache/glint/samples/mni152_t1_09a.nii.gz`); without it the bench uses the
//! built-in phantom at 192^3 so it still runs. The comparison with VTK in the same run
//! is scripts/bench/bench-vtk.

use criterion::{criterion_group, criterion_main, Criterion};
use glint_lobe::LobeKind;
use glint_render::{LobeSpec, ReadOptions, Renderer, Scene, SceneLobe};

#[path = "common/mni152_scene.rs"]
mod common;

/// The benchmark scene (`common::mni152_scene`).
fn scene() -> Scene {
    common::mni152_scene("mni152 bench")
}

fn bench(c: &mut Criterion) {
    let scene = scene();
    let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let mut group = c.benchmark_group("render_mni152_512");
    group.sample_size(10);
    // `hw`: the default unit's table (glint_hw::Config::default(), v = 4).
    for kind in [
        SceneLobe::Float(LobeKind::Exact),
        SceneLobe::Float(LobeKind::EnergyFit),
        SceneLobe::Hw,
    ] {
        let scene = Scene {
            lobe: LobeSpec {
                kind,
                ..scene.lobe.clone()
            },
            ..scene.clone()
        };
        // Classified once (the first render), as `glint render --repeat` and an
        // interactive viewer do.
        let resolved = renderer.resolve(&scene).unwrap();
        renderer.render_resolved(resolved.clone(), &|_| {}).unwrap();
        group.bench_function(kind.name(), |b| {
            b.iter(|| renderer.render_resolved(resolved.clone(), &|_| {}).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
