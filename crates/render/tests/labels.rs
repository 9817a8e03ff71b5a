//! Label maps as a scene layer: surfaces in their table colours, a legend of what is
//! shown, placement by the label grid's own affine, and one clear error for each bad
//! input.

use std::path::{Path, PathBuf};

use glint_io::{nifti, Endian, Samples, Volume};
use glint_render::{
    CameraSpec, Input, LabelSpec, MaterialOverrides, Projection, ReadOptions, RenderError,
    Renderer, Scene, View,
};

/// Two 6-voxel cubes side by side along x, labels `a` then `b`, in a 16^3 grid of
/// 1 mm voxels shifted by `offset` mm.
fn two_blocks(dir: &Path, name: &str, a: u8, b: u8, offset: f64) -> PathBuf {
    let n = 16;
    let values: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            let inside = (5..11).contains(&y) && (5..11).contains(&z);
            match x {
                2..=7 if inside => a,
                8..=13 if inside => b,
                _ => 0,
            }
        })
        .collect();
    let mut vol = Volume::new([n; 3], [1.0; 3], Samples::U8(values)).unwrap();
    for r in 0..3 {
        vol.affine[r][3] = offset;
    }
    let path = dir.join(name);
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    path
}

/// A scene of the label map alone, seen from the front, unshaded so a pixel is its
/// label's colour.
fn scene(labels: LabelSpec) -> Scene {
    Scene {
        input: Input::None,
        labels: Some(labels),
        size: [96, 96],
        ssaa: Some(1),
        camera: CameraSpec {
            view: View::Anterior,
            projection: Projection::Orthographic,
            ..CameraSpec::default()
        },
        material: MaterialOverrides {
            ambient: Some(1.0),
            diffuse: Some(0.0),
            specular: Some(0.0),
            shade: Some(false),
        },
        ..Scene::default()
    }
}

fn render(scene: &Scene) -> Result<glint_render::Rendered, RenderError> {
    Renderer::open(scene, &ReadOptions::default())?.render(scene, &|_| {})
}

/// sRGB 0-255 to linear, as the renderer converts table colours.
fn linear(c: [u8; 3]) -> [f32; 3] {
    c.map(|x| glint_render::srgb_to_linear(f64::from(x) / 255.0) as f32)
}

#[test]
fn labels_render_in_their_table_colours_with_a_legend() {
    let dir = tempfile::tempdir().unwrap();
    // FreeSurfer's 17 Left-Hippocampus (220, 216, 20) and 18 Left-Amygdala
    // (103, 255, 255), as FreeSurferColorLUT.txt lists them.
    let path = two_blocks(dir.path(), "aseg.nii", 17, 18, 0.0);
    let rendered = render(&scene(LabelSpec::new(&path))).unwrap();
    // The file is named like FreeSurfer's: its table was chosen and written back.
    let spec = rendered.scene.labels.as_ref().unwrap();
    assert_eq!(spec.table.as_deref(), Some("freesurfer"));
    // Its grid is isotropic: the smoothing of one voxel.
    assert_eq!(spec.smoothing, Some(1.0));
    let legend = rendered.legend.as_ref().unwrap();
    let names: Vec<&str> = legend.entries.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["Left-Hippocampus", "Left-Amygdala"]);
    // Seen from the front (looking towards posterior), the patient's right (+x in
    // RAS) is on the image's left: label 18 at x 8..13 is left of label 17.
    let img = &rendered.image;
    let at = |x: u32, y: u32| img.rgb[(y * img.width + x) as usize];
    let (right, left) = (at(30, 48), at(66, 48));
    let (hippo, amygdala) = (linear([220, 216, 20]), linear([103, 255, 255]));
    for k in 0..3 {
        assert!((left[k] - hippo[k]).abs() < 0.02, "{left:?} vs {hippo:?}");
        assert!(
            (right[k] - amygdala[k]).abs() < 0.02,
            "{right:?} vs {amygdala:?}"
        );
    }
    // The corners are background.
    assert_eq!(at(1, 1), [0.0; 3]);
}

#[test]
fn show_and_hide_select_by_name_or_number() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_blocks(dir.path(), "seg.nii", 5, 52, 0.0);
    let mut spec = LabelSpec::new(&path);
    spec.table = Some("totalsegmentator".into());
    spec.hide = vec!["Liver".into()];
    let r = render(&scene(spec.clone())).unwrap();
    let names: Vec<String> = r.legend.unwrap().entries.into_iter().map(|e| e.0).collect();
    assert_eq!(names, ["aorta"]);
    // Only the aorta block is drawn: no pixel has the liver's colour, many the aorta's.
    let table = glint_render::label_maps::LabelTable::totalsegmentator();
    let count = |c: [u8; 3]| {
        let want = linear(c);
        r.image
            .rgb
            .iter()
            .filter(|p| (0..3).all(|k| (p[k] - want[k]).abs() < 0.02))
            .count()
    };
    assert_eq!(count(table.color_of(5)), 0);
    assert!(count(table.color_of(52)) > 500);
    spec.hide.clear();
    spec.show = vec!["5".into()];
    let r = render(&scene(spec.clone())).unwrap();
    assert_eq!(r.legend.unwrap().entries[0].0, "liver");
    // A name not in the table, and a label not in the map, are refused.
    spec.show = vec!["livr".into()];
    let err = glint_io::one_line(&render(&scene(spec.clone())).unwrap_err());
    assert!(
        err.contains("unknown label \"livr\"") && err.contains("liver"),
        "{err}"
    );
    spec.show = vec!["spleen".into()];
    let err = glint_io::one_line(&render(&scene(spec)).unwrap_err());
    assert!(
        err.contains("spleen") && err.contains("not in the map"),
        "{err}"
    );
}

#[test]
fn a_label_grid_away_from_the_volume_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let far = two_blocks(dir.path(), "far.nii", 1, 2, 5000.0);
    let volume = Volume::new([8; 3], [1.0; 3], Samples::U8(vec![100; 512])).unwrap();
    let vpath = dir.path().join("vol.nii");
    nifti::write(&vpath, &volume, false, Endian::Little).unwrap();
    let mut s = scene(LabelSpec::new(&far));
    s.input = Input::Path(vpath.clone());
    let err = glint_io::one_line(&render(&s).unwrap_err());
    assert!(err.contains("does not overlap the volume"), "{err}");
    // Overlapping: renders, with the volume.
    s.labels = Some(LabelSpec::new(two_blocks(
        dir.path(),
        "near.nii",
        1,
        2,
        -4.0,
    )));
    assert!(render(&s).is_ok());
}

#[test]
fn a_non_label_volume_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let v = Volume::new([4; 3], [1.0; 3], Samples::F32(vec![0.25; 64])).unwrap();
    let path = dir.path().join("prob.nii");
    nifti::write(&path, &v, false, Endian::Little).unwrap();
    let err = glint_io::one_line(&render(&scene(LabelSpec::new(&path))).unwrap_err());
    assert!(
        err.contains("prob.nii") && err.contains("whole numbers"),
        "{err}"
    );
}

#[test]
fn scenes_without_labels_serialise_as_before_and_labels_round_trip() {
    let json = Scene::default().to_json().unwrap();
    assert!(!json.contains("labels"));
    let mut spec = LabelSpec::new("seg.nii.gz");
    spec.show = vec!["liver".into()];
    spec.legend = false;
    let s = Scene {
        input: Input::None,
        labels: Some(spec),
        ..Scene::default()
    };
    assert_eq!(Scene::from_json(&s.to_json().unwrap()).unwrap(), s);
    // A scene file with labels and no input key has no volume.
    let text = r#"{"version": 1, "labels": {"path": "seg.nii.gz"}}"#;
    assert_eq!(Scene::from_json(text).unwrap().input, Input::None);
}

/// A scene of the label map at `path` drawn as a label volume `how` in the frame of
/// the same file read as an intensity volume through a transparent transfer
/// function, so every pixel shows the labels alone.
fn volume_scene(path: &Path, spec: LabelSpec) -> Scene {
    let mut s = scene(spec);
    s.input = Input::Path(path.to_path_buf());
    s.mode = glint_render::RenderMode::Composite;
    s.transfer_function = Some(
        glint_render::TransferFunction::from_flat(&[0.0, 0.0, 100.0, 0.0], &[0.0, 1.0, 1.0, 1.0])
            .unwrap(),
    );
    s
}

#[test]
fn labels_as_a_volume_show_their_table_colours_unblended() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_blocks(dir.path(), "aseg.nii", 17, 18, 0.0);
    let mut spec = LabelSpec::new(&path);
    spec.render_as = glint_render::LabelsAs::Volume;
    let r = render(&volume_scene(&path, spec.clone())).unwrap();
    let names: Vec<String> = r.legend.unwrap().entries.into_iter().map(|e| e.0).collect();
    assert_eq!(names, ["Left-Hippocampus", "Left-Amygdala"]);
    let (hippo, amygdala) = (linear([220, 216, 20]), linear([103, 255, 255]));
    let close = |p: [f32; 3], c: [f32; 3]| (0..3).all(|k| (p[k] - c[k]).abs() < 1e-5);
    let (mut h, mut a) = (0, 0);
    for (i, p) in r.image.rgb.iter().enumerate() {
        // Nearest-label classification: a pixel is one label's colour or the
        // background, never a blend of the two where they meet.
        if close(*p, hippo) {
            h += 1;
        } else if close(*p, amygdala) {
            a += 1;
        } else {
            assert!(close(*p, [0.0; 3]), "pixel {i}: {p:?}");
            assert_eq!(r.image.alpha[i], 0.0);
        }
    }
    assert!(h > 300 && a > 300, "{h} hippocampus, {a} amygdala pixels");
    // As the surfaces: the patient's right (label 18, higher x) on the image's left.
    let img = &r.image;
    let at = |x: u32, y: u32| img.rgb[(y * img.width + x) as usize];
    assert!(close(at(30, 48), amygdala) && close(at(66, 48), hippo));
    // The scene says how the labels were drawn.
    assert_eq!(
        r.scene.labels.as_ref().unwrap().render_as,
        glint_render::LabelsAs::Volume
    );
    let json = r.scene.to_json().unwrap();
    assert!(json.contains("\"render_as\": \"volume\""), "{json}");

    // A hidden label is not drawn; a translucent one lets the background through.
    spec.hide = vec!["Left-Amygdala".into()];
    spec.opacity.insert("17".into(), 0.2);
    let r = render(&volume_scene(&path, spec.clone())).unwrap();
    assert!(!r.image.rgb.iter().any(|p| close(*p, amygdala)));
    let partial = r
        .image
        .alpha
        .iter()
        .filter(|a| **a > 0.1 && **a < 0.9)
        .count();
    assert!(partial > 300, "{partial} translucent pixels");
    assert!(r.image.alpha.iter().all(|a| *a < 0.9));
}

#[test]
fn a_label_volume_needs_a_volume_and_opacity_needs_a_label_volume() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_blocks(dir.path(), "aseg.nii", 17, 18, 0.0);
    let mut spec = LabelSpec::new(&path);
    spec.render_as = glint_render::LabelsAs::Volume;
    let err = glint_io::one_line(&render(&scene(spec)).unwrap_err());
    assert!(err.contains("ray cast in a volume's frame"), "{err}");
    let mut spec = LabelSpec::new(&path);
    spec.opacity.insert("17".into(), 0.5);
    let err = glint_io::one_line(&render(&scene(spec.clone())).unwrap_err());
    assert!(err.contains("per-label opacity"), "{err}");
    spec.render_as = glint_render::LabelsAs::Volume;
    spec.opacity.insert("17".into(), 1.5);
    let err = glint_io::one_line(&render(&volume_scene(&path, spec)).unwrap_err());
    assert!(err.contains("opacity 1.5"), "{err}");
}

#[test]
fn a_table_alpha_is_the_label_volume_default_opacity_and_surfaces_stay_opaque() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_blocks(dir.path(), "seg.nii", 1, 2, 0.0);
    let table = dir.path().join("t.json");
    std::fs::write(
        &table,
        r#"{"1": {"name": "faint", "color": [200, 0, 0], "alpha": 0.2}, "2": {"name": "solid", "color": [0, 0, 200]}}"#,
    )
    .unwrap();
    let mut spec = LabelSpec::new(&path);
    spec.table = Some(table.display().to_string());
    spec.render_as = glint_render::LabelsAs::Volume;
    let alpha_where = |r: &glint_render::Rendered, c: [f32; 3]| -> Vec<f32> {
        let img = &r.image;
        (0..img.rgb.len())
            .filter(|&i| {
                let p = img.rgb[i];
                let k = if c[0] > 0.0 { 0 } else { 2 };
                p[k] > 0.05 && p[2 - k] < 1e-6
            })
            .map(|i| img.alpha[i])
            .collect()
    };
    let r = render(&volume_scene(&path, spec.clone())).unwrap();
    let faint = alpha_where(&r, [1.0, 0.0, 0.0]);
    let solid = alpha_where(&r, [0.0, 0.0, 1.0]);
    assert!(
        faint.len() > 300 && solid.len() > 300,
        "{} {}",
        faint.len(),
        solid.len()
    );
    // Alpha 0.2 per voxel length over 6 voxels: 1 - 0.8^6 = 0.74, well below opaque.
    assert!(faint.iter().all(|a| *a < 0.9), "{faint:?}");
    assert!(solid.iter().filter(|a| **a == 1.0).count() > 300);
    // --label-opacity overrides the table.
    spec.opacity.insert("faint".into(), 1.0);
    let r = render(&volume_scene(&path, spec.clone())).unwrap();
    assert!(
        alpha_where(&r, [1.0, 0.0, 0.0])
            .iter()
            .filter(|a| **a == 1.0)
            .count()
            > 300
    );
    // Surfaces are drawn opaque whatever the table says (the rasterizer does not blend).
    spec.opacity.clear();
    spec.render_as = glint_render::LabelsAs::Surfaces;
    let r = render(&scene(spec)).unwrap();
    assert!(r.image.alpha.iter().filter(|a| **a == 1.0).count() > 1000);
}

#[test]
fn a_crop_box_cuts_label_surfaces_and_picks_go_through_what_it_removes() {
    let dir = tempfile::tempdir().unwrap();
    let path = two_blocks(dir.path(), "aseg.nii", 17, 18, 0.0);
    let whole = scene(LabelSpec::new(&path));
    // Keep x <= 10.5 mm: through the middle of label 18's block (x 8..13).
    let cut = 10.5f32;
    let mut cropped = whole.clone();
    cropped.crop = Some(glint_render::CropBox {
        min: [-100.0; 3],
        max: [f64::from(cut), 100.0, 100.0],
    });
    let mut r = Renderer::open(&whole, &ReadOptions::default()).unwrap();
    let camera = r.camera(&whole).unwrap();
    assert_eq!(
        r.camera(&cropped).unwrap(),
        camera,
        "the crop keeps the framing"
    );
    let a = r.render(&whole, &|_| {}).unwrap().image;
    let b = r.render(&cropped, &|_| {}).unwrap().image;
    let (w, h) = (a.width, a.height);
    let (mut lost, mut kept) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            // Orthographic from the front: a pixel's world x is its ray's.
            let (o, _) = camera.ray(x as f32, y as f32, w, h);
            let k = (y * w + x) as usize;
            if o.x > cut + 0.01 {
                assert_eq!((b.rgb[k], b.alpha[k]), ([0.0; 3], 0.0), "({x}, {y})");
                lost += usize::from(a.alpha[k] > 0.0);
            } else if o.x < cut - 0.01 {
                assert_eq!((b.rgb[k], b.alpha[k]), (a.rgb[k], a.alpha[k]), "({x}, {y})");
                kept += usize::from(a.alpha[k] > 0.0);
            }
        }
    }
    assert!(lost > 100 && kept > 300, "{lost} lost, {kept} kept");
    // A pick where the crop removed the surface meets nothing; beside it, label 17.
    let x = (0..w)
        .find(|&x| {
            let (o, _) = camera.ray(x as f32, 48.0, w, h);
            o.x > cut + 1.0 && o.x < 13.0
        })
        .unwrap();
    assert!(r.pick(&whole, f64::from(x) + 0.5, 48.5).unwrap().is_some());
    assert!(r
        .pick(&cropped, f64::from(x) + 0.5, 48.5)
        .unwrap()
        .is_none());
}
