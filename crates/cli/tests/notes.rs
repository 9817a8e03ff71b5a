//! Issue 47 item 3: what the reader skipped reaches the user of every command, as
//! `glint info` shows it: on stderr of `render`, `mesh` and `view` (not under `-q`),
//! and in the notes of a `batch` row.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use dicom_core::value::PrimitiveValue;
use dicom_core::{dicom_value, VR};
use dicom_dictionary_std::tags;
use glint_testkit::dicom::{ds, put, write, ImageHeader, CT_STORAGE, EXPLICIT_LE};

/// RT Structure Set Storage (PS3.4 B.5).
const RT_STRUCT: &str = "1.2.840.10008.5.1.4.1.1.481.3";

/// What the note names: the file and its SOP class.
const NOTE: &str = "skipped 1 object(s): rtstruct.dcm (not an image: RT Structure Set Storage)";

/// A radiotherapy export as it comes: four 8x8 CT slices (a bright block in the
/// middle) beside an RT structure set, which is not an image.
fn export(dir: &Path) {
    for k in 0..4u16 {
        let mut o = ImageHeader {
            instance: format!("1.2.3.4.{k}"),
            ..ImageHeader::ct(8, 8)
        }
        .object();
        put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&[1.0, 1.0]));
        put(
            &mut o,
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        );
        let z = 2.0 * f64::from(k);
        put(
            &mut o,
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            ds(&[0.0, 0.0, z]),
        );
        let px: Vec<u16> = (0..64)
            .map(|i| {
                if (2..6).contains(&(i % 8)) && (2..6).contains(&(i / 8)) {
                    1000
                } else {
                    0
                }
            })
            .collect();
        put(
            &mut o,
            tags::PIXEL_DATA,
            VR::OW,
            PrimitiveValue::U16(px.into()),
        );
        write(&dir.join(format!("ct{k}.dcm")), o, CT_STORAGE, EXPLICIT_LE);
    }
    let mut rs = dicom_object::InMemDicomObject::new_empty();
    put(
        &mut rs,
        tags::SOP_CLASS_UID,
        VR::UI,
        dicom_value!(Str, RT_STRUCT),
    );
    put(
        &mut rs,
        tags::SOP_INSTANCE_UID,
        VR::UI,
        dicom_value!(Str, "1.2.3.5.1"),
    );
    put(
        &mut rs,
        tags::SERIES_INSTANCE_UID,
        VR::UI,
        dicom_value!(Str, "1.2.3.5"),
    );
    put(
        &mut rs,
        tags::MODALITY,
        VR::CS,
        dicom_value!(Str, "RTSTRUCT"),
    );
    put(
        &mut rs,
        tags::STRUCTURE_SET_LABEL,
        VR::SH,
        dicom_value!(Str, "organs"),
    );
    write(&dir.join("rtstruct.dcm"), rs, RT_STRUCT, EXPLICIT_LE);
}

/// `glint ARGS` must succeed; its stderr.
fn stderr_of(args: &[&str]) -> String {
    let out = common::glint(args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{args:?}: {err}");
    err
}

#[test]
fn render_names_the_skipped_object_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("export");
    std::fs::create_dir(&study).unwrap();
    export(&study);
    let png = dir.path().join("out.png");
    let (s, p) = (study.to_str().unwrap(), png.to_str().unwrap());
    let err = stderr_of(&["render", s, "--size", "24x24", "-o", p]);
    assert!(err.contains(&format!("glint: {s}: {NOTE}")), "{err}");
    assert!(png.is_file());
    let err = stderr_of(&["render", s, "--size", "24x24", "-q", "-o", p]);
    assert!(!err.contains("skipped"), "{err}");
}

#[test]
fn mesh_names_the_skipped_object_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("export");
    std::fs::create_dir(&study).unwrap();
    export(&study);
    let stl = dir.path().join("block.stl");
    let (s, o) = (study.to_str().unwrap(), stl.to_str().unwrap());
    let err = stderr_of(&["mesh", s, "--iso", "500", "-o", o]);
    assert!(err.contains(&format!("glint: {s}: {NOTE}")), "{err}");
    assert!(stl.is_file());
    let err = stderr_of(&["mesh", s, "--iso", "500", "-q", "-o", o]);
    assert!(!err.contains("skipped"), "{err}");
}

/// `glint view`'s stderr up to the line that says where to open it (on stdout).
fn view_stderr(args: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["view", "--port", "0"])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Serving: the URL line is printed once the volume is read and the notes are out.
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    stdout.read_line(&mut line).unwrap();
    child.kill().unwrap();
    let output = child.wait_with_output().unwrap();
    assert!(line.contains("glint view: open http"), "{line}");
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn view_names_the_skipped_object_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    export(dir.path());
    let s = dir.path().to_str().unwrap();
    let err = view_stderr(&[s]);
    assert!(err.contains(&format!("glint: {s}: {NOTE}")), "{err}");
    let err = view_stderr(&[s, "-q"]);
    assert!(!err.contains("skipped"), "{err}");
}

#[test]
fn a_batch_row_names_the_skipped_object() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study/patient1");
    std::fs::create_dir_all(&study).unwrap();
    export(&study);
    let out = dir.path().join("out");
    let inputs = dir.path().join("study");
    let args = [
        "batch",
        inputs.to_str().unwrap(),
        "--size",
        "24x24",
        "-o",
        out.to_str().unwrap(),
    ];
    stderr_of(&args);
    let results = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let row: serde_json::Value = serde_json::from_str(results.lines().next().unwrap()).unwrap();
    assert_eq!(row["status"], "ok", "{row}");
    let notes: Vec<&str> = row["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str())
        .collect();
    assert!(notes.contains(&NOTE), "{notes:?}");
}
