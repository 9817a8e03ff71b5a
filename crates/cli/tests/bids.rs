//! Issue 47 item 2: `glint batch` on a BIDS dataset as BIDS apps run: participants,
//! sessions and suffixes chosen, the output a BIDS derivatives dataset.

mod common;

use std::path::Path;

use glint_io::{nifti, Endian};
use glint_render::Phantom;

/// A BIDS dataset: sub-01 (T1w, T2w), sub-02 with sessions pre and post (T1w each).
fn dataset(root: &Path) {
    std::fs::write(
        root.join("dataset_description.json"),
        br#"{"Name": "tiny", "BIDSVersion": "1.9.0"}"#,
    )
    .unwrap();
    let vol = Phantom::SheppLogan.volume(16).unwrap();
    for rel in [
        "sub-01/anat/sub-01_T1w.nii.gz",
        "sub-01/anat/sub-01_T2w.nii.gz",
        "sub-02/ses-pre/anat/sub-02_ses-pre_T1w.nii.gz",
        "sub-02/ses-post/anat/sub-02_ses-post_T1w.nii.gz",
    ] {
        let path = root.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        nifti::write(&path, &vol, true, Endian::Little).unwrap();
    }
}

#[test]
fn participants_sessions_and_suffixes_make_a_derivatives_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("ds");
    std::fs::create_dir(&ds).unwrap();
    dataset(&ds);
    let out = ds.join("derivatives/glint");
    let (d, o) = (ds.to_str().unwrap(), out.to_str().unwrap());
    let base = ["batch", d, "-o", o, "--size", "16x16", "-q"];
    let run = |extra: &[&str]| common::ok(&[&base[..], extra].concat());
    run(&[
        "--participant-label",
        "sub-02",
        "--session-label",
        "pre",
        "--suffix",
        "T1w",
    ]);
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let ids: Vec<String> = results
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["id"].to_string())
        .collect();
    assert_eq!(ids, ["\"sub-02_ses-pre_T1w\""]);
    let text = std::fs::read_to_string(out.join("dataset_description.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["DatasetType"], "derivative");
    let by = &v["GeneratedBy"][0];
    assert_eq!(by["Name"], "glint");
    assert_eq!(by["Version"], env!("CARGO_PKG_VERSION"));
    let command = by["Description"].as_str().unwrap();
    assert!(
        command.contains("batch") && command.contains("--participant-label sub-02"),
        "{command}"
    );
    // sub-01's T2w; sub-02 has none, so naming it too would be an error (as a typo).
    run(&["--participant-label", "01", "--suffix", "T2w"]);
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert_eq!(results.lines().count(), 1, "{results}");
    assert!(results.contains("sub-01_T2w"), "{results}");
}

#[test]
fn a_label_no_input_has_is_one_line_and_nothing_is_made() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    let out = dir.path().join("out");
    let (d, o) = (dir.path().to_str().unwrap(), out.to_str().unwrap());
    let err = common::fails(&["batch", d, "-o", o, "--participant-label", "03"]);
    assert!(
        err.contains("no input of participant label '03' (the inputs have 01, 02)"),
        "{err}"
    );
    assert!(!out.exists());
}
