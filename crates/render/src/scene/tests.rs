//! Tests of scenes: JSON, resolution, rendering through the Renderer.

use std::sync::Arc;

use glint_core::Timings;
use glint_hw::Config as HwConfig;
use glint_lobe::{Geometry, LobeKind, Specular};
use glint_raster::SURFACE_COLOR;
use glint_volume::LightingModel;

use super::*;
use crate::meshes::{DEFAULT_SSAA, SURFACE_SHININESS};
use crate::{Plan, Renderer};

fn small() -> Scene {
    Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 24,
        },
        size: [24, 20],
        ..Scene::default()
    }
}

/// The field follows the scene's prefilter: rebuilt from the kept volume when a
/// scene asks for another one, with a different image; a renderer given only a
/// field refuses another prefilter with a typed error.
#[test]
fn the_field_follows_the_scenes_prefilter() {
    let scene = small();
    assert_eq!(scene.prefilter, Prefilter::Binomial);
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let smooth = r.render(&scene, &|_| {}).unwrap();
    assert_eq!(r.field().unwrap().prefilter(), Prefilter::Binomial);
    let raw_scene = Scene {
        prefilter: Prefilter::None,
        ..scene.clone()
    };
    let raw = r.render(&raw_scene, &|_| {}).unwrap();
    assert_eq!(r.field().unwrap().prefilter(), Prefilter::None);
    assert_ne!(smooth.image.rgb, raw.image.rgb);
    assert_eq!(raw.scene.prefilter, Prefilter::None);
    let volume = scene.input.open().unwrap();
    let mut fixed = Renderer::from_source(Field::new(&volume).unwrap(), None).unwrap();
    let err = fixed.render(&scene, &|_| {}).unwrap_err();
    assert!(matches!(err, RenderError::Parameter(_)), "{err}");
    assert!(fixed.render(&raw_scene, &|_| {}).is_ok());
    assert!(
        Renderer::from_source(Field::new(&volume).unwrap(), Some(Prefilter::Binomial)).is_err()
    );
    // Opened for the scene, the field is built once, with its prefilter.
    let opened = Renderer::open(&raw_scene, &ReadOptions::default()).unwrap();
    assert_eq!(opened.field().unwrap().prefilter(), Prefilter::None);
}

/// The scene's filter: trilinear by default and then absent from the JSON; tricubic
/// (set by a patch, as the viewer and Python do) reconstructs the same field's bricks
/// (no second field built) with another image in every lighting model, and back to
/// trilinear gives the first image bit for bit; a given field refuses another filter.
#[test]
fn the_field_follows_the_scenes_filter() {
    let scene = small();
    assert_eq!(scene.filter, Filter::Trilinear);
    assert!(!serde_json::to_string(&scene)
        .unwrap()
        .contains("\"filter\""));
    let cubic_scene = scene
        .patch(
            serde_json::json!({"filter": "tricubic"})
                .as_object()
                .unwrap(),
        )
        .unwrap();
    assert_eq!(cubic_scene.filter, Filter::Tricubic);
    assert!(serde_json::to_string(&cubic_scene)
        .unwrap()
        .contains("\"filter\":\"tricubic\""));
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    for lighting in [
        LightingModel::Local,
        LightingModel::Shadows,
        LightingModel::Path,
    ] {
        let with = |s: &Scene| Scene {
            lighting: Lighting {
                model: lighting,
                spp: (lighting == LightingModel::Path).then_some(2),
                ..Lighting::default()
            },
            ..s.clone()
        };
        let linear = r.render(&with(&scene), &|_| {}).unwrap();
        let cubic = r.render(&with(&cubic_scene), &|_| {}).unwrap();
        assert_eq!(r.field().unwrap().filter(), Filter::Tricubic);
        assert_ne!(linear.image.rgb, cubic.image.rgb, "{lighting:?}");
        let again = r.render(&with(&scene), &|_| {}).unwrap();
        assert_eq!(linear.image.rgb, again.image.rgb, "{lighting:?}");
    }
    let last = r.render(&cubic_scene, &|_| {}).unwrap();
    assert_eq!(fields_built(&last.timings), 1);
    let volume = scene.input.open().unwrap();
    let mut fixed = Renderer::from_source(Field::new(&volume).unwrap(), None).unwrap();
    let raw = Scene {
        prefilter: Prefilter::None,
        ..cubic_scene
    };
    let err = fixed.render(&raw, &|_| {}).unwrap_err();
    assert!(err.to_string().contains("filter tricubic"), "{err}");
}

/// How many times `timings` built a field.
fn fields_built(timings: &Timings) -> usize {
    let stages = timings.stages().iter();
    stages.filter(|(s, _)| *s == "field: prepare").count()
}

/// A renderer opened with a scene of another prefilter than the default, with
/// meshes, builds one field and reads the meshes once (issue 40): rendering the
/// scene builds and reads nothing more.
#[test]
fn opened_with_its_scene_a_renderer_builds_one_field_and_reads_meshes_once() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene {
        meshes: vec![MeshSpec::new(octahedron(dir.path()))],
        prefilter: Prefilter::None,
        ..small()
    };
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let read = r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m));
    assert!(read.is_some());
    let rendered = r.render(&scene, &|_| {}).unwrap();
    assert_eq!(r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m)), read);
    assert_eq!(fields_built(&rendered.timings), 1);
    let meshes = rendered.timings.stages().iter();
    assert_eq!(meshes.filter(|(s, _)| *s == "meshes").count(), 1);
    assert_eq!(r.field().unwrap().prefilter(), Prefilter::None);
}

/// A renderer of a shared volume keeps the caller's volume (no copy) and builds its
/// field at the first scene's prefilter, once; given a prefilter, it builds it now.
#[test]
fn a_renderer_of_a_shared_volume_builds_its_field_for_the_first_scene() {
    let scene = Scene {
        prefilter: Prefilter::None,
        ..small()
    };
    let volume = Arc::new(scene.input.open().unwrap());
    let mut r = Renderer::from_source(volume.clone(), None).unwrap();
    assert_eq!(Arc::strong_count(&volume), 2);
    assert!(r.field().is_none());
    let lazy = r.render(&scene, &|_| {}).unwrap();
    assert_eq!(r.field().unwrap().prefilter(), Prefilter::None);
    assert_eq!(fields_built(&lazy.timings), 1);
    let mut eager = Renderer::from_source(volume.clone(), Some(Prefilter::None)).unwrap();
    assert_eq!(eager.field().unwrap().prefilter(), Prefilter::None);
    let now = eager.render(&scene, &|_| {}).unwrap();
    assert_eq!(fields_built(&now.timings), 1);
    assert_eq!(now.image, lazy.image);
    let mut opened = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    assert_eq!(opened.render(&scene, &|_| {}).unwrap().image, lazy.image);
}

#[test]
fn json_round_trip_keeps_every_field() {
    let mut scene = small();
    scene.mode = RenderMode::Iso;
    scene.iso = Some(0.25);
    scene.lobe = LobeSpec {
        kind: LobeKind::Schlick.into(),
        n: Some(33.0),
        v: 3,
        geometry: Geometry::Blinn,
        hw: None,
    };
    scene.lights.push(Light {
        azimuth: -40.0,
        elevation: 20.0,
        intensity: 0.5,
    });
    scene.material.specular = Some(0.7);
    let json = scene.to_json().unwrap();
    assert!(json.contains("\"version\": 1"), "{json}");
    assert!(
        json.contains("\"schlick\"") && json.contains("\"blinn\""),
        "{json}"
    );
    assert_eq!(Scene::from_json(&json).unwrap(), scene);
}

#[test]
fn missing_fields_take_defaults_and_unknown_ones_are_refused() {
    assert_eq!(Scene::from_json("{}").unwrap(), Scene::default());
    let err = Scene::from_json(r#"{"colour": 1}"#)
        .unwrap_err()
        .to_string();
    assert!(err.contains("colour"), "{err}");
    let err = Scene::from_json(r#"{"version": 7}"#)
        .unwrap_err()
        .to_string();
    assert!(err.contains("version 7"), "{err}");
    let err = Scene::from_json(r#"{"lobe": {"kind": "cosine"}}"#)
        .unwrap_err()
        .to_string();
    assert!(err.contains("cosine"), "{err}");
}

#[test]
fn hw_lobes_parse_by_name_and_take_v_from_the_unit() {
    let parse = |lobe: &str| Scene::from_json(&format!(r#"{{"lobe": {lobe}}}"#));
    let plain = parse(r#"{"kind": "hw", "n": 40}"#).unwrap().lobe;
    assert_eq!(plain.kind, SceneLobe::Hw);
    assert_eq!((plain.v, plain.hw), (HwConfig::default().v, None));
    // v left out: the unit's; given: kept as written (resolution checks it).
    let v3 = r#""hw": {"v": 3, "square_frac": [14, 14, 12]}"#;
    let lobe = parse(&format!(r#"{{"kind": "HW", {v3}}}"#)).unwrap().lobe;
    assert_eq!(lobe.v, 3);
    assert_eq!(lobe.hw.as_ref().unwrap().square_frac, [14, 14, 12]);
    assert_eq!(
        lobe.hw.as_ref().unwrap().out_bits,
        HwConfig::default().out_bits
    );
    let lobe = parse(&format!(r#"{{"kind": "hw", "v": 5, {v3}}}"#))
        .unwrap()
        .lobe;
    assert_eq!(lobe.v, 5);
    // Float lobes keep the default v whatever the unit says.
    let lobe = parse(&format!(r#"{{"kind": "g", {v3}}}"#)).unwrap().lobe;
    assert_eq!((lobe.kind, lobe.v), (LobeKind::SlopeFit.into(), 4));
    // Unknown fields of the unit are refused, naming the path.
    let err = parse(r#"{"kind": "hw", "hw": {"out_bitz": 8}}"#).unwrap_err();
    assert!(err.to_string().contains("lobe.hw"), "{err}");
    let err = parse(r#"{"kind": "hardware"}"#).unwrap_err().to_string();
    assert!(err.contains("hardware") && err.contains("hw"), "{err}");
    for lobe in SceneLobe::ALL {
        assert_eq!(lobe.name().parse::<SceneLobe>().unwrap(), lobe);
    }
}

#[test]
fn a_resolved_hw_scene_names_the_whole_unit_and_round_trips() {
    let field = Field::new(&small().input.open().unwrap()).unwrap();
    let scene = Scene::from_json(
        r#"{"input": {"phantom": {"name": "shepp-logan", "size": 24}},
        "size": [24, 20], "lobe": {"kind": "hw", "n": 40}}"#,
    )
    .unwrap();
    let resolved = scene.resolve_for(&field).unwrap();
    assert_eq!(resolved.scene.lobe.hw, Some(HwConfig::default()));
    let json = resolved.scene.to_json().unwrap();
    for field in ["\"hw\"", "out_bits", "square_frac", "coefficients"] {
        assert!(json.contains(field), "{field} missing: {json}");
    }
    let again = Scene::from_json(&json).unwrap();
    assert_eq!(again, resolved.scene);
    assert_eq!(again.resolve_for(&field).unwrap().scene, resolved.scene);
}

#[test]
fn a_resolved_hw_lobe_is_the_units_output_per_cosine() {
    use glint_hw::{Input as HwInput, Unit};
    let field = Field::new(&small().input.open().unwrap()).unwrap();
    for (config, n) in [
        (HwConfig::default(), 40.4),
        (
            HwConfig {
                out_bits: 12,
                ..HwConfig::default()
            },
            100.0,
        ),
    ] {
        let scene = Scene {
            lobe: LobeSpec {
                n: Some(n),
                geometry: Geometry::Blinn,
                ..LobeSpec::hw(config.clone())
            },
            ..small()
        };
        let resolved = scene.resolve_for(&field).unwrap();
        let specular = resolved.shader.specular();
        let unit = Unit::new(config).unwrap();
        let full = unit.full_scale();
        // n is rounded to the unit's integer input.
        let n_in = n.round() as u32;
        let mut distinct = std::collections::BTreeSet::new();
        for i in 0..=20_000 {
            let c = 0.9f32 + 0.1 * i as f32 / 20_000.0;
            let out = unit
                .eval(&HwInput {
                    cos: unit.cos_code(f64::from(c)).unwrap(),
                    n: n_in,
                    ks: [full; 3],
                })
                .unwrap();
            let want = (out.rgb[0] as f64 / full as f64) as f32;
            assert_eq!(specular.eval(c).to_bits(), want.to_bits(), "n {n}, c {c}");
            distinct.insert(out.rgb[0]);
        }
        assert!(distinct.len() > 100, "{} output codes", distinct.len());
    }
}

#[test]
fn contradictory_or_bad_hw_lobes_are_typed_errors() {
    let field = Field::new(&small().input.open().unwrap()).unwrap();
    let hw = |v: u32, config: Option<HwConfig>, n: f64| Scene {
        lobe: LobeSpec {
            kind: SceneLobe::Hw,
            v,
            n: Some(n),
            hw: config,
            ..LobeSpec::default()
        },
        ..small()
    };
    let err = hw(3, None, 40.0).resolve_for(&field).unwrap_err();
    assert!(
        matches!(err, RenderError::HwV { lobe: 3, unit: 4 }),
        "{err:?}"
    );
    let v3 = HwConfig {
        v: 3,
        square_frac: vec![14, 14, 12],
        ..HwConfig::default()
    };
    assert!(hw(3, Some(v3.clone()), 40.0).resolve_for(&field).is_ok());
    let err = hw(4, Some(v3), 40.0).resolve_for(&field).unwrap_err();
    assert!(
        matches!(err, RenderError::HwV { lobe: 4, unit: 3 }),
        "{err:?}"
    );
    let bad = HwConfig {
        out_bits: 0,
        ..HwConfig::default()
    };
    let err = hw(4, Some(bad), 40.0).resolve_for(&field).unwrap_err();
    assert!(matches!(err, RenderError::HwConfig(_)), "{err:?}");
    let err = hw(4, None, 1024.0).resolve_for(&field).unwrap_err();
    assert!(matches!(err, RenderError::HwN { .. }), "{err:?}");
    // A float lobe ignores the unit, even an invalid one.
    let mut k = hw(
        4,
        Some(HwConfig {
            v: 11,
            ..HwConfig::default()
        }),
        40.0,
    );
    k.lobe.kind = LobeKind::EnergyFit.into();
    assert!(k.resolve_for(&field).is_ok());
}

#[test]
fn a_renderer_builds_a_units_table_once_per_configuration_and_n() {
    let scene = Scene {
        lobe: LobeSpec {
            n: Some(30.0),
            ..LobeSpec::hw(HwConfig::default())
        },
        ..small()
    };
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let mut table = |s: &Scene| match r.resolve(s).unwrap().shader.specular() {
        Specular::Table(t) => t.clone(),
        Specular::Lobe(l) => panic!("a hw scene resolved to {l:?}"),
    };
    let first = table(&scene);
    // Another frame of the viewer: the camera moved.
    let mut moved = scene.clone();
    moved.camera.azimuth = 20.0;
    assert!(Arc::ptr_eq(&first, &table(&moved)));
    // Another n: another table.
    moved.lobe.n = Some(31.0);
    assert!(!Arc::ptr_eq(&first, &table(&moved)));
}

#[test]
fn resolution_writes_its_choices_back_and_is_idempotent() {
    let field = Field::new(&small().input.open().unwrap()).unwrap();
    for mode in [RenderMode::Composite, RenderMode::Iso, RenderMode::Mip] {
        let scene = Scene { mode, ..small() };
        let first = scene.resolve_for(&field).unwrap();
        let s = &first.scene;
        assert!(s.lobe.n.is_some() && s.material.ambient.is_some());
        assert!(s.preset.is_some() || s.transfer_function.is_some());
        assert_eq!(s.iso.is_some(), mode == RenderMode::Iso);
        // Resolving the resolved scene chooses nothing new.
        let again = s.resolve_for(&field).unwrap();
        assert_eq!(&again.scene, s, "{mode:?}");
        let tf = |r: &Resolved| match &r.plan {
            Plan::Volume { tf, .. } => tf.clone(),
            Plan::Surface { .. } => panic!("a volume scene resolved to a surface plan"),
        };
        assert_eq!(tf(&again), tf(&first));
    }
}

#[test]
fn bad_scenes_are_refused_with_the_reason() {
    let field = Field::new(&small().input.open().unwrap()).unwrap();
    let cases: Vec<(Scene, &str)> = vec![
        (
            Scene {
                lights: vec![],
                ..small()
            },
            "no light",
        ),
        (
            Scene {
                iso: Some(1.0),
                ..small()
            },
            "iso",
        ),
        (
            Scene {
                preset: Some("ct-nonsense".into()),
                ..small()
            },
            "ct-nonsense",
        ),
        (
            Scene {
                step: 0.0,
                ..small()
            },
            "step",
        ),
        (
            Scene {
                size: [0, 4],
                ..small()
            },
            "image size",
        ),
        (
            Scene {
                gate: f64::NAN,
                ..small()
            },
            "gate",
        ),
    ];
    for (scene, needle) in cases {
        let err = scene.resolve_for(&field).unwrap_err().to_string();
        assert!(err.contains(needle), "'{err}' lacks '{needle}'");
    }
}

#[test]
fn a_renderer_reuses_its_classification_only_when_it_still_applies() {
    let scene = small();
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let classified = |t: &Timings| t.stages().iter().any(|(s, _)| *s == "classify");
    let first = r.render(&scene, &|_| {}).unwrap();
    assert!(classified(&first.timings));
    // Another view and lobe: same classification.
    let moved = Scene {
        camera: CameraSpec {
            azimuth: 30.0,
            ..scene.camera
        },
        lobe: LobeSpec {
            kind: LobeKind::Exact.into(),
            ..scene.lobe.clone()
        },
        ..scene.clone()
    };
    let second = r.render(&moved, &|_| {}).unwrap();
    assert!(!classified(&second.timings));
    assert_ne!(second.image.rgb, first.image.rgb);
    // Another step: classified again, and the image equals a fresh renderer's.
    let finer = Scene {
        step: 0.25,
        ..scene.clone()
    };
    let third = r.render(&finer, &|_| {}).unwrap();
    assert!(classified(&third.timings));
    let fresh = Renderer::open(&scene, &ReadOptions::default())
        .unwrap()
        .render(&finer, &|_| {})
        .unwrap();
    // The pixels, not the march's counters: with the bricked field (issue 31) a
    // renderer whose bricks were built by earlier frames counts a few samples fewer
    // in skipped space than a fresh one, for the same image.
    assert_eq!(third.image.rgb, fresh.image.rgb);
    assert_eq!(third.image.alpha, fresh.image.alpha);
}

/// A closed octahedron as OBJ in `dir`.
fn octahedron(dir: &std::path::Path) -> PathBuf {
    let path = dir.join("octa.obj");
    std::fs::write(
        &path,
        "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
         f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n",
    )
    .unwrap();
    path
}

#[test]
fn a_mesh_scene_resolves_once_and_reads_its_meshes_once() {
    let dir = tempfile::tempdir().unwrap();
    let json = format!(
        r#"{{"meshes": [{{"path": {:?}}}], "size": [32, 24]}}"#,
        octahedron(dir.path())
    );
    // Meshes without an input key: no volume.
    let scene = Scene::from_json(&json).unwrap();
    assert_eq!(scene.input, Input::None);
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    assert!(r.field().is_none());
    let first = r.render(&scene, &|_| {}).unwrap();
    let s = &first.scene;
    assert_eq!(s.mode, RenderMode::Surface);
    assert_eq!(s.ssaa, Some(DEFAULT_SSAA));
    assert_eq!(s.lobe.n, Some(SURFACE_SHININESS));
    assert_eq!(s.meshes[0].color, Some(SURFACE_COLOR));
    assert!(first.colors.is_none());
    // The resolved scene chooses nothing new and renders the same image.
    let mut again = s.clone();
    again.derived = None;
    let second = r.render(&again, &|_| {}).unwrap();
    assert_eq!(second.scene, first.scene);
    assert_eq!(second.image, first.image);
    // Its JSON names the lack of a volume, and reads back to the same scene.
    let text = again.to_json().unwrap();
    assert!(text.contains(r#""input": "none""#), "{text}");
    assert_eq!(Scene::from_json(&text).unwrap(), again);
    // The octahedron covers the centre of the image.
    assert!(first.image.alpha[12 * 32 + 16] > 0.99);
    // A new camera reuses the meshes read (same Arc).
    let moved = Scene {
        camera: CameraSpec {
            azimuth: 40.0,
            ..again.camera
        },
        ..again.clone()
    };
    let before = r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m));
    r.render(&moved, &|_| {}).unwrap();
    assert_eq!(r.meshes.as_ref().map(|(_, m)| Arc::as_ptr(m)), before);
}

/// An octahedron of radius `r` about `c` (mm) as OBJ in `dir`.
fn octahedron_at(dir: &std::path::Path, c: [f32; 3], r: f32) -> PathBuf {
    let path = dir.join("octa-at.obj");
    let mut text = String::new();
    for a in 0..3 {
        for sign in [1.0, -1.0] {
            let mut p = c;
            p[a] += sign * r;
            text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
    }
    text += "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
    std::fs::write(&path, text).unwrap();
    path
}

/// A volume with meshes in a ray-cast mode: the meshes are drawn with the
/// volume's camera and the volume composited over them. Pixels no mesh covers are
/// the volume's alone; a mesh between the eye and the volume hides it, so there
/// the image is the meshes' alone (the surface renderer with the same camera).
#[test]
fn a_volume_with_meshes_composites_the_volume_over_them() {
    let dir = tempfile::tempdir().unwrap();
    let base = Scene {
        size: [40, 40],
        ssaa: Some(1),
        ..small()
    };
    // In front of the phantom (it spans +-100 mm; anterior is +y).
    let scene = Scene {
        meshes: vec![MeshSpec::new(octahedron_at(
            dir.path(),
            [0.0, 160.0, 0.0],
            40.0,
        ))],
        ..base.clone()
    };
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let resolved = r.resolve(&scene).unwrap();
    let Plan::Volume {
        meshes: Some(layer),
        ..
    } = &resolved.plan
    else {
        panic!("a volume plan with meshes expected");
    };
    let layer = layer.clone();
    let shader = resolved.shader.clone();
    let both = r.render(&scene, &|_| {}).unwrap();
    let alone = r.render(&base, &|_| {}).unwrap();
    let camera = r.camera(&base).unwrap();
    let meshes = layer
        .surfaces
        .as_ref()
        .unwrap()
        .render(&camera, &shader, &layer.settings, None)
        .unwrap();
    let (mut covered, mut uncovered) = (0, 0);
    for i in 0..40 * 40 {
        if meshes.alpha[i] == 0.0 {
            assert_eq!(both.image.rgb[i], alone.image.rgb[i], "pixel {i}");
            assert_eq!(both.image.alpha[i], alone.image.alpha[i], "pixel {i}");
            uncovered += 1;
        } else if meshes.alpha[i] == 1.0 {
            for c in 0..3 {
                let d = (both.image.rgb[i][c] - meshes.rgb[i][c]).abs();
                assert!(
                    d < 1e-6,
                    "pixel {i}: {:?} vs {:?}",
                    both.image.rgb[i],
                    meshes.rgb[i]
                );
            }
            assert_eq!(both.image.alpha[i], 1.0);
            covered += 1;
        }
    }
    // The mesh covers the middle of the image and the volume shows around it.
    assert!(
        meshes.alpha[20 * 40 + 20] == 1.0 && covered > 50,
        "{covered}"
    );
    assert!(
        (0..1600).any(|i| meshes.alpha[i] == 0.0 && alone.image.alpha[i] > 0.5),
        "{uncovered}"
    );
    // The dumped scene names the meshes and renders again bit for bit.
    let mut again = both.scene.clone();
    again.derived = None;
    assert_eq!(again.meshes.len(), 1);
    assert_eq!(again.mode, RenderMode::Composite);
    let text = again.to_json().unwrap();
    let reread = Scene::from_json(&text).unwrap();
    let fresh = Renderer::open(&reread, &ReadOptions::default())
        .unwrap()
        .render(&reread, &|_| {})
        .unwrap();
    assert_eq!(fresh.image, both.image);
}

#[test]
fn a_volume_with_meshes_in_surface_mode_joins_its_isosurface() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene {
        meshes: vec![MeshSpec::new(octahedron(dir.path()))],
        mode: RenderMode::Surface,
        ..small()
    };
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    // The phantom's isosurface joins the octahedron.
    let resolved = r.resolve(&scene).unwrap();
    assert!(resolved.scene.iso.is_some());
    let Plan::Surface { surfaces, .. } = &resolved.plan else {
        panic!("a surface plan expected");
    };
    assert_eq!(surfaces.mesh_count(), 2);
}

/// Meshes occlude the volume's light in `shadows` and `path` (issue 29): two small
/// octahedra in the empty corners of the phantom's box, left and right of it, with a
/// light from the image's side: where the local images with and without them agree
/// (pixels the meshes do not cover), the `shadows` image with them is nowhere
/// brighter and darker in some (without occluders the two are the same); the
/// occupancy is built for `shadows` and `path` with meshes only, and kept while the
/// camera moves.
#[test]
fn meshes_shadow_the_volume_in_shadows_and_path() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = |name: &str, x: f32| {
        let path = octahedron_at(dir.path(), [x, 0.0, 0.0], 15.0);
        let named = dir.path().join(name);
        std::fs::rename(&path, &named).unwrap();
        MeshSpec::new(named)
    };
    let base = Scene {
        input: Input::Phantom {
            name: Phantom::SheppLogan,
            size: 48,
        },
        size: [48, 40],
        ssaa: Some(1),
        lights: vec![Light {
            azimuth: 90.0,
            elevation: 0.0,
            intensity: 1.0,
        }],
        ..Scene::default()
    };
    let with = Scene {
        meshes: vec![mesh("left.obj", -82.0), mesh("right.obj", 82.0)],
        ..base.clone()
    };
    let lit = |s: &Scene, model: LightingModel| Scene {
        lighting: Lighting {
            model,
            spp: (model == LightingModel::Path).then_some(1),
            ..Lighting::default()
        },
        ..s.clone()
    };
    let mut r = Renderer::open(&with, &ReadOptions::default()).unwrap();
    let stage = |t: &Timings| t.stages().iter().any(|(s, _)| *s == "occluders");
    let local_with = r
        .render(&lit(&with, LightingModel::Local), &|_| {})
        .unwrap();
    assert!(!stage(&local_with.timings), "local builds no occupancy");
    let shadows_with = r
        .render(&lit(&with, LightingModel::Shadows), &|_| {})
        .unwrap();
    assert!(
        stage(&shadows_with.timings),
        "shadows with meshes builds it"
    );
    let path_with = r.render(&lit(&with, LightingModel::Path), &|_| {}).unwrap();
    assert!(!stage(&path_with.timings), "path reuses the occupancy");
    let mut moved = lit(&with, LightingModel::Shadows);
    moved.camera.azimuth = 20.0;
    assert!(!stage(&r.render(&moved, &|_| {}).unwrap().timings), "kept");
    let mut alone = Renderer::open(&base, &ReadOptions::default()).unwrap();
    let local_alone = alone
        .render(&lit(&base, LightingModel::Local), &|_| {})
        .unwrap();
    let shadows_alone = alone
        .render(&lit(&base, LightingModel::Shadows), &|_| {})
        .unwrap();
    assert!(!stage(&shadows_alone.timings), "no meshes, no occupancy");
    let (mut open, mut darker, mut drop) = (0, 0, 0.0f32);
    for i in 0..48 * 40 {
        if local_with.image.rgb[i] != local_alone.image.rgb[i] {
            continue;
        }
        open += 1;
        let (a, b) = (shadows_with.image.rgb[i], shadows_alone.image.rgb[i]);
        for c in 0..3 {
            assert!(a[c] <= b[c] + 1e-6, "pixel {i}: {a:?} brighter than {b:?}");
        }
        darker += usize::from(a[1] < b[1] - 1e-3);
        drop = drop.max(b[1] - a[1]);
    }
    assert!(open > 48 * 40 / 2, "{open} pixels uncovered");
    assert!(
        darker >= 20 && drop > 0.01,
        "{darker} darker pixels, largest drop {drop}"
    );
}

/// Issue 43: window and level remap the transfer function's value axis: in MIP without
/// a preset (the grey ramp over the robust range) the value at the level reads the
/// ramp's centre, the window's ends its foot and top; the field is not rebuilt, only
/// the classification; a preset clears the window.
#[test]
fn window_and_level_remap_the_transfer_function() {
    let scene = Scene {
        mode: RenderMode::Mip,
        ..small()
    };
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let plain = r.render(&scene, &|_| {}).unwrap();
    let (lo, hi) = r.field().unwrap().robust_range();
    let own = plain
        .scene
        .derived
        .as_ref()
        .unwrap()
        .transfer_function
        .as_ref()
        .unwrap()
        .window_level();
    assert!((own.window - (hi - lo) as f64).abs() < 1e-5, "{own:?}");
    assert!((own.level - (lo + hi) as f64 / 2.0).abs() < 1e-5, "{own:?}");
    let target = WindowLevel {
        window: 0.1,
        level: 0.25,
    };
    let mut windowed = plain.scene.clone();
    windowed.set_window_level(Some(target)).unwrap();
    let out = r.render(&windowed, &|_| {}).unwrap();
    let d = out.scene.derived.as_ref().unwrap();
    let tf = d.transfer_function.as_ref().unwrap();
    assert!((tf.opacity_at(0.25) - 0.5).abs() < 1e-9);
    assert!(tf.opacity_at(0.2) < 1e-9 && tf.opacity_at(0.19) == 0.0);
    assert!(tf.opacity_at(0.3) > 1.0 - 1e-9 && tf.opacity_at(0.31) == 1.0);
    assert!((tf.opacity_at(0.275) - 0.75).abs() < 1e-9);
    let got = tf.window_level();
    assert!(
        (got.window - 0.1).abs() < 1e-9 && (got.level - 0.25).abs() < 1e-9,
        "{got:?}"
    );
    assert_ne!(out.image.rgb, plain.image.rgb);
    // The resolved scene keeps the ramp and the window: it renders the same again.
    assert_eq!(out.scene.window_level, Some(target));
    let again = r.render(&out.scene, &|_| {}).unwrap();
    assert_eq!(again.image.rgb, out.image.rgb);
    assert_eq!(fields_built(&again.timings), 1, "the field is built once");
    // A preset starts from its own window; a bad width is refused.
    let next = out
        .scene
        .patch(
            serde_json::json!({"preset": "ct-bone"})
                .as_object()
                .unwrap(),
        )
        .unwrap();
    assert_eq!(next.window_level, None);
    let bad = out
        .scene
        .patch(
            serde_json::json!({"window_level": {"window": 0, "level": 1}})
                .as_object()
                .unwrap(),
        )
        .unwrap();
    let err = r.render(&bad, &|_| {}).unwrap_err().to_string();
    assert!(err.contains("window 0"), "{err}");
    assert!(windowed
        .set_window_level(Some(WindowLevel {
            window: -1.0,
            level: 0.0
        }))
        .is_err());
}

/// A path scene of the small phantom lit by `map` alone.
fn env_scene(map: &str) -> Scene {
    Scene {
        lights: vec![],
        lighting: Lighting {
            model: LightingModel::Path,
            spp: Some(2),
            environment_map: Some(map.into()),
            ..Lighting::default()
        },
        ..small()
    }
}

/// `shadows` takes a map as its median cut's directional lights: lit by it alone
/// the image is not black, the map's rotation and intensity change it, and the lights
/// fit beside the scene's own lights (8 alone, 4 beside a headlight).
#[test]
fn shadows_takes_an_environment_map_as_directional_lights() {
    let mut r = Renderer::open(&small(), &ReadOptions::default()).unwrap();
    let mut scene = env_scene("studio");
    scene.lighting.model = LightingModel::Shadows;
    scene.lighting.spp = None;
    let mean =
        |img: &glint_core::Image| img.rgb.iter().flatten().map(|&c| f64::from(c)).sum::<f64>();
    let lit = r.render(&scene, &|_| {}).unwrap().image;
    assert!(mean(&lit) > 0.0);
    let mut turned = scene.clone();
    turned.lighting.environment_rotation = Some(180.0);
    assert_ne!(r.render(&turned, &|_| {}).unwrap().image.rgb, lit.rgb);
    let mut dim = scene.clone();
    dim.lighting.environment_intensity = Some(0.25);
    assert!(mean(&r.render(&dim, &|_| {}).unwrap().image) < mean(&lit));
    // Beside a headlight the map gets 4 lights (8 would be refused as too many).
    let mut headlit = scene.clone();
    headlit.lights = vec![glint_core::Light::HEADLIGHT];
    assert!(mean(&r.render(&headlit, &|_| {}).unwrap().image) > mean(&lit));
}

/// A Radiance `.hdr` of `w x h` texels, written flat (no run-length encoding) with
/// image-rs's encoder.
fn write_hdr(path: &std::path::Path, w: usize, h: usize, f: impl Fn(usize, usize) -> f32) {
    let px: Vec<image::Rgb<f32>> = (0..w * h)
        .map(|i| image::Rgb([f(i % w, i / w); 3]))
        .collect();
    let file = std::fs::File::create(path).unwrap();
    image::codecs::hdr::HdrEncoder::new(file)
        .encode(&px, w, h)
        .unwrap();
}

/// An OpenEXR file of `w x h` texels of radiance `f`.
fn write_exr(path: &std::path::Path, w: usize, h: usize, f: impl Fn(usize, usize) -> f32 + Sync) {
    exr::prelude::write_rgb_file(path, w, h, |x, y| (f(x, y), f(x, y), f(x, y))).unwrap();
}

#[test]
fn an_environment_map_lights_a_path_scene_and_resolves_its_defaults() {
    let scene = env_scene("studio");
    let mut r = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let out = r.render(&scene, &|_| {}).unwrap();
    let l = &out.scene.lighting;
    // The map replaces the uniform environment: its settings written back, the
    // uniform radiance left unset.
    assert_eq!(l.environment, None);
    assert_eq!(l.environment_rotation, Some(0.0));
    assert_eq!(l.environment_intensity, Some(1.0));
    assert!(out.image.rgb.iter().any(|c| c[1] > 0.01));
    // Turned and brighter: another image; the resolved scene renders the same image.
    let mut turned = scene.clone();
    turned.lighting.environment_rotation = Some(120.0);
    turned.lighting.environment_intensity = Some(2.0);
    let other = r.render(&turned, &|_| {}).unwrap();
    assert_ne!(other.image.rgb, out.image.rgb);
    let again = r.render(&out.scene, &|_| {}).unwrap();
    assert_eq!(again.image.rgb, out.image.rgb);
    // Files: .hdr and .exr of one constant radiance give the constant map's image.
    let dir = tempfile::tempdir().unwrap();
    let (hdr, exr) = (dir.path().join("c.hdr"), dir.path().join("c.exr"));
    write_hdr(&hdr, 16, 8, |_, _| 0.5);
    write_exr(&exr, 16, 8, |_, _| 0.5);
    let a = r
        .render(&env_scene(hdr.to_str().unwrap()), &|_| {})
        .unwrap();
    let b = r
        .render(&env_scene(exr.to_str().unwrap()), &|_| {})
        .unwrap();
    assert_eq!(a.image.rgb, b.image.rgb);
    // The viewer's and Python's patch reaches the field.
    let patched = small()
        .patch(
            serde_json::json!({"lighting": {"model": "path", "environment_map": "studio"}})
                .as_object()
                .unwrap(),
        )
        .unwrap();
    assert_eq!(patched.lighting.environment_map.as_deref(), Some("studio"));
}

#[test]
fn bad_environment_maps_and_settings_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    write_hdr(&p("good.hdr"), 16, 8, |x, _| x as f32);
    let bytes = std::fs::read(p("good.hdr")).unwrap();
    std::fs::write(p("truncated.hdr"), &bytes[..bytes.len() - 40]).unwrap();
    std::fs::write(p("garbage.hdr"), b"not a radiance file\n").unwrap();
    // A header of 100000 x 100000 texels and no data: refused before allocating.
    std::fs::write(
        p("huge.hdr"),
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n\x01\x02",
    )
    .unwrap();
    write_exr(&p("nan.exr"), 8, 4, |x, y| {
        if (x, y) == (3, 2) {
            f32::NAN
        } else {
            1.0
        }
    });
    write_exr(
        &p("negative.exr"),
        8,
        4,
        |x, _| if x == 5 { -1.0 } else { 1.0 },
    );
    std::fs::write(p("garbage.exr"), b"v/1\x01 not an exr").unwrap();
    std::fs::write(p("map.png"), b"").unwrap();
    for (file, want) in [
        ("truncated.hdr", ""),
        ("garbage.hdr", ""),
        ("huge.hdr", "100000x100000"),
        ("nan.exr", "(3, 2)"),
        ("negative.exr", "(5, 0)"),
        ("garbage.exr", ""),
        ("map.png", ".hdr or .exr"),
        ("missing.hdr", ""),
    ] {
        let e = load_environment(p(file).to_str().unwrap()).unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(e, glint_core::RenderError::EnvironmentMap { .. }),
            "{file}: {e:?}"
        );
        assert!(!msg.contains('\n') && msg.contains(want), "{file}: {msg}");
        assert!(msg.contains(file), "{file}: {msg}");
    }
    assert!(load_environment(p("good.hdr").to_str().unwrap()).is_ok());
    assert!(load_environment("nowhere")
        .unwrap_err()
        .to_string()
        .contains("studio"));
    // Settings: a map's settings need a map; a map and a uniform radiance conflict;
    // another model does not take a map; a bad rotation or intensity.
    let mut r = Renderer::open(&small(), &ReadOptions::default()).unwrap();
    let mut no_map = env_scene("studio");
    no_map.lighting.environment_map = None;
    no_map.lighting.environment_rotation = Some(10.0);
    let mut both = env_scene("studio");
    both.lighting.environment = Some(0.5);
    let mut shadows = env_scene("studio");
    shadows.lighting.model = LightingModel::Shadows;
    shadows.lighting.spp = None;
    shadows.lights = vec![glint_core::Light::HEADLIGHT];
    shadows.lighting.environment = Some(0.5);
    let mut crowded = shadows.clone();
    crowded.lighting.environment = None;
    crowded.lights = vec![glint_core::Light::HEADLIGHT; glint_core::MAX_LIGHTS];
    let mut rotation = env_scene("studio");
    rotation.lighting.environment_rotation = Some(1000.0);
    let mut intensity = env_scene("studio");
    intensity.lighting.environment_intensity = Some(-1.0);
    for (scene, want) in [
        (no_map, "need an environment_map"),
        (both, "give one"),
        (shadows, "not used by shadows"),
        (crowded, "needs room for its lights"),
        (rotation, "rotation"),
        (intensity, "intensity"),
    ] {
        let msg = r.render(&scene, &|_| {}).unwrap_err().to_string();
        assert!(!msg.contains('\n') && msg.contains(want), "{msg}");
    }
}

#[test]
fn the_device_is_cpu_by_default_left_out_of_the_json_and_parsed_by_name() {
    let scene = small();
    assert_eq!(scene.device, Device::Cpu);
    assert!(!scene.to_json().unwrap().contains("device"));
    let gpu = Scene {
        device: Device::Gpu,
        ..small()
    };
    let json = gpu.to_json().unwrap();
    assert!(json.contains("\"device\": \"gpu\""), "{json}");
    assert_eq!(Scene::from_json(&json).unwrap(), gpu);
    let bad = json.replace("\"gpu\"", "\"tpu\"");
    let e = Scene::from_json(&bad).unwrap_err().to_string();
    assert!(e.contains("tpu") && !e.contains('\n'), "{e}");
    assert_eq!("AUTO".parse::<Device>().unwrap(), Device::Auto);
}

#[test]
fn device_gpu_refuses_what_it_does_not_render_and_auto_falls_back_with_a_note() {
    let mut renderer = Renderer::open(&small(), &ReadOptions::default()).unwrap();
    let cpu = renderer.render(&small(), &|_| {}).unwrap().image;
    // `path` is not on the GPU yet: `gpu` is one line naming it, `auto` renders
    // the CPU's image and says why.
    let mut path = small();
    path.lighting.model = LightingModel::Path;
    path.lighting.spp = Some(2);
    let refused = Scene {
        device: Device::Gpu,
        ..path.clone()
    };
    let e = renderer.render(&refused, &|_| {}).unwrap_err().to_string();
    assert!(
        e.contains("--device gpu") && e.contains("path") && !e.contains('\n'),
        "{e}"
    );
    let auto = Scene {
        device: Device::Auto,
        ..path.clone()
    };
    let got = renderer.render(&auto, &|_| {}).unwrap().image;
    let want = renderer.render(&path, &|_| {}).unwrap().image;
    assert_eq!(got.rgb, want.rgb);
    let notes = renderer.device_notes();
    assert!(notes.iter().any(|n| n.contains("path")), "{notes:?}");
    // Taken: each note is handed out once.
    assert!(renderer.device_notes().is_empty());
    // `local` under `auto`: the GPU's frame on a hardware GPU, else (lavapipe, no
    // adapter, no `gpu` feature) the CPU's image with a note.
    let auto = Scene {
        device: Device::Auto,
        ..small()
    };
    let got = renderer.render(&auto, &|_| {}).unwrap().image;
    if !renderer.device_notes().is_empty() {
        assert_eq!(got.rgb, cpu.rgb);
    }
}
