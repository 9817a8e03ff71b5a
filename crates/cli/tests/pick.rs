//! `glint pick --at X,Y`: the point a pixel shows, as JSON, checked against an
//! analytic ball; points off the image and malformed points fail with one line
//! (issue 43 item 2).

mod common;

use std::path::{Path, PathBuf};

use common::{fails, ok};
use glint_io::{nifti, Endian, Samples, Volume};
use serde_json::Value;

/// Grid edge, voxel size (mm) and radius (mm) of the ball.
const N: usize = 32;
const SPACING: f64 = 1.5;
const R: f64 = 15.0;

fn centre() -> f64 {
    SPACING * (N - 1) as f64 / 2.0
}

/// The value of voxel `ijk`: its depth below the ball's surface, mm.
fn depth_below(ijk: [u64; 3]) -> f64 {
    let d2: f64 = ijk
        .iter()
        .map(|&i| (i as f64 * SPACING - centre()).powi(2))
        .sum();
    R - d2.sqrt()
}

/// The ball written as NIfTI.
fn ball(dir: &Path) -> PathBuf {
    let mut values = Vec::with_capacity(N * N * N);
    for k in 0..N as u64 {
        for j in 0..N as u64 {
            for i in 0..N as u64 {
                values.push(depth_below([i, j, k]) as f32);
            }
        }
    }
    let vol = Volume::new([N; 3], [SPACING; 3], Samples::F32(values)).unwrap();
    let path = dir.join("ball.nii");
    nifti::write(&path, &vol, false, Endian::Little).unwrap();
    path
}

/// `glint pick BALL --mode iso --iso 0 ... EXTRA`, its JSON.
fn pick(ball: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "pick",
        ball.to_str().unwrap(),
        "--mode",
        "iso",
        "--iso",
        "0",
        "--size",
        "64x48",
        "--projection",
        "orthographic",
    ];
    args.extend(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

fn vec3(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|a| v[a].as_f64().unwrap())
}

#[test]
fn a_pick_prints_the_balls_front_point_its_voxel_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let path = ball(dir.path());
    let p = pick(&path, &["--at", "32,24"]);
    assert_eq!(p["object"]["kind"], "volume", "{p}");
    assert_eq!((p["x"].as_f64(), p["y"].as_f64()), (Some(32.0), Some(24.0)));
    let w = vec3(&p["world_mm"]);
    // On the sphere within half a voxel, on the side facing the (anterior, +y) camera.
    let r = w.iter().map(|x| (x - centre()).powi(2)).sum::<f64>().sqrt();
    assert!((r - R).abs() < SPACING / 2.0, "{p}");
    assert!(w[1] - centre() > R * 0.9, "{p}");
    let voxel = vec3(&p["voxel"]);
    for a in 0..3 {
        assert!((voxel[a] * SPACING - w[a]).abs() < 1e-3, "{p}");
    }
    let nearest = [0, 1, 2].map(|a| p["voxel_nearest"][a].as_u64().unwrap());
    let value = p["value"].as_f64().unwrap();
    assert!((value - depth_below(nearest)).abs() < 1e-4, "{p}");
    assert_eq!(p["label"], Value::Null);
}

#[test]
fn several_points_print_an_array_with_null_where_nothing_shows() {
    let dir = tempfile::tempdir().unwrap();
    let path = ball(dir.path());
    let p = pick(&path, &["--at", "32,24", "--at", "0.5,0.5"]);
    let picks = p.as_array().unwrap();
    assert_eq!(picks.len(), 2);
    assert_eq!(picks[0]["object"]["kind"], "volume");
    assert_eq!(picks[1], Value::Null, "the corner shows nothing");
}

#[test]
fn points_off_the_image_and_malformed_points_fail_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = ball(dir.path());
    let path = path.to_str().unwrap();
    let base = ["pick", path, "--size", "64x48"];
    let run = |extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend(extra);
        fails(&args)
    };
    let e = run(&["--at", "64,10"]);
    assert!(e.contains("off the 64x48 image"), "{e}");
    let e = run(&["--at", "-1,10"]);
    assert!(e.contains("off the 64x48 image"), "{e}");
    let e = run(&["--at", "10"]);
    assert!(e.contains("expected X,Y"), "{e}");
    let e = run(&["--at", "10,nan"]);
    assert!(e.contains("expected X,Y"), "{e}");
    let e = run(&["--at", "10,10", "--opacity", "1.5"]);
    assert!(e.contains("threshold"), "{e}");
    // --at is required (clap's usage error, its first line).
    let e = fails(&["pick", path]);
    assert!(e.contains("required arguments"), "{e}");
}

#[test]
fn help_says_what_the_coordinates_and_fields_are() {
    let help = ok(&["pick", "--help"]);
    for needle in ["top-left corner", "--opacity", "world_mm", "HU", "Examples"] {
        assert!(help.contains(needle), "{needle} missing from:\n{help}");
    }
}
