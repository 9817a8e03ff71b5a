//! `glint batch` as a user runs it: a directory of good and broken volumes, the exit
//! status counting the failures, a rerun that does nothing.

mod common;

use std::collections::BTreeMap;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::Output;

use glint_io::{nifti, Endian};
use glint_render::Phantom;

/// `glint batch ARGS`.
fn glint(args: &[&str]) -> Output {
    common::glint(&[&["batch"], args].concat())
}

/// Every file below `dir` and its inode (an atomic rewrite gives a new one).
fn inodes(dir: &Path) -> BTreeMap<PathBuf, u64> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let ino = std::fs::metadata(&p).unwrap().ino();
                files.insert(p, ino);
            }
        }
    }
    files
}

#[test]
fn a_directory_of_good_and_broken_volumes() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    for (name, size) in [("one", 24), ("two", 28)] {
        let vol = Phantom::Head.volume(size).unwrap();
        nifti::write(
            &data.join(format!("{name}.nii")),
            &vol,
            false,
            Endian::Little,
        )
        .unwrap();
    }
    std::fs::write(data.join("bad.nii.gz"), b"not gzip").unwrap();
    std::fs::write(data.join("worse.nii"), b"").unwrap();
    let out = dir.path().join("qc");
    let (d, o) = (data.to_str().unwrap(), out.to_str().unwrap());
    let args = [d, "-o", o, "--size", "32x24", "--slices", "--jobs", "2"];

    let first = glint(&args);
    let stderr = String::from_utf8_lossy(&first.stderr);
    // Two failed inputs: exit status 2, one line for each, and the summary.
    assert_eq!(first.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("glint batch: bad: ") && stderr.contains("glint batch: worse: "));
    assert!(
        stderr.contains("2 made (0 up to date), 2 failed"),
        "{stderr}"
    );
    for id in ["one", "two"] {
        for file in ["mosaic.png", "slices.png", "scene.json", "row.json"] {
            assert!(out.join(id).join(file).is_file(), "{id}/{file}");
        }
    }
    let table = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert_eq!(table.lines().count(), 4);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert_eq!(html.matches("<img class=\"thumb").count(), 4);

    // A rerun makes nothing and rewrites nothing.
    let before = inodes(&out);
    let again = glint(&args);
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("2 made (2 up to date), 2 failed"),
        "{stderr}"
    );
    assert_eq!(inodes(&out), before);

    // --force makes them again: new rows (their seconds), the same pictures (files
    // that would not change are not rewritten).
    let png = std::fs::read(out.join("one/mosaic.png")).unwrap();
    let forced = glint(&[&args[..], &["--force", "-q"]].concat());
    assert_eq!(forced.status.code(), Some(2));
    assert!(forced.stderr.is_empty(), "-q prints nothing");
    let row = out.join("one/row.json");
    assert_ne!(inodes(&out)[&row], before[&row]);
    assert_eq!(std::fs::read(out.join("one/mosaic.png")).unwrap(), png);
}

#[test]
fn errors_that_stop_the_run_exit_1_before_any_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("qc");
    let o = out.to_str().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let pattern = dir.path().join("*.nrrd");
    let file = dir.path().join("a.nii");
    std::fs::write(&file, b"x").unwrap();
    for args in [
        vec![empty.to_str().unwrap(), "-o", o],
        vec![pattern.to_str().unwrap(), "-o", o],
        vec![file.to_str().unwrap(), "-o", o, "--preset", "ct-nonsense"],
    ] {
        let run = glint(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.starts_with("glint: error: "), "{stderr}");
        assert!(!out.exists(), "{args:?} made the output directory");
    }
}
