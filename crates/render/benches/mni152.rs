//! Criterion bench: the MNI152 T1 template at 512x512, step 0.5 voxel, composite with
//! shading (mr-t2-brain preset), view from the left, with `--lobe exact` and `--lobe k`.
//!
//! The template comes from scripts/fetch-samples (path in `GLINT_MNI152`, default
//! `~/.cache/glint/samples/mni152_t1_09a.nii.gz`); without it the bench uses the
//! built-in phantom at 192^3 so it still runs. The comparison with VTK in the same run
//! is scripts/bench-vtk.

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use glint_lobe::{Geometry, LobeKind};
use glint_render::{
    phantom, preset, CameraSpec, Classification, Field, Light, RenderSettings, Shader, View,
};

fn load() -> (glint_io::Volume, &'static str) {
    let path = std::env::var_os("GLINT_MNI152")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let home = std::env::var_os("HOME").unwrap_or_default();
            PathBuf::from(home).join(".cache/glint/samples/mni152_t1_09a.nii.gz")
        });
    match glint_io::read_volume(&path, &glint_io::ReadOptions::default()) {
        Ok(v) => (v, "mr-t2-brain"),
        Err(e) => {
            eprintln!("mni152 bench: {e}; using the phantom (run scripts/fetch-samples)");
            (phantom::shepp_logan(192).unwrap(), "phantom")
        }
    }
}

fn bench(c: &mut Criterion) {
    let (volume, preset_name) = load();
    let field = Field::new(&volume).unwrap();
    let p = preset(preset_name).unwrap();
    let tf = p.transfer_function(field.range().1 as f64).unwrap();
    let settings = RenderSettings {
        width: 512,
        height: 512,
        step: 0.5,
        camera: CameraSpec {
            view: View::Left,
            ..Default::default()
        },
        ..Default::default()
    };
    // Classified once, as `glint render --repeat` and an interactive viewer do.
    let class = Classification::new(&field, &tf, &settings).unwrap();
    let cam = class.camera(&settings).unwrap();
    let lights = vec![(Light::HEADLIGHT.direction(&cam), 1.0)];
    let mut group = c.benchmark_group("render_mni152_512");
    group.sample_size(10);
    for kind in [LobeKind::Exact, LobeKind::EnergyFit] {
        let m = p.material();
        let shader = Shader::new(
            kind,
            m.power as f64,
            4,
            Geometry::Phong,
            m,
            lights.clone(),
            0.0,
        )
        .unwrap();
        group.bench_function(kind.name(), |b| {
            b.iter(|| class.render(&shader, &settings, &|_| {}).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
