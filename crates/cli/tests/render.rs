//! `glint render` end to end on DICOM that other readers accept leniently.

use std::path::Path;
use std::process::Command;

use dicom_core::value::PrimitiveValue;
use dicom_core::VR;
use dicom_dictionary_std::tags;
use glint_testkit::dicom::{ds, put, write, ImageHeader, CT_STORAGE, EXPLICIT_LE};

/// An 8x8, 4-frame, 16-bit CT image with PixelSpacing and SpacingBetweenSlices but no
/// ImagePositionPatient or ImageOrientationPatient: a stack in frame order whose
/// geometry the reader must assume.
fn write_frames_without_positions(path: &Path) {
    let mut o = ImageHeader {
        frames: Some(4),
        ..ImageHeader::ct(8, 8)
    }
    .object();
    put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&[1.0, 1.0]));
    put(&mut o, tags::SPACING_BETWEEN_SLICES, VR::DS, ds(&[2.0]));
    // A bright block in the middle, so the render has something to show.
    let px: Vec<u16> = (0..8 * 8 * 4)
        .map(|i| {
            let (x, y) = (i % 8, i / 8 % 8);
            if (2..6).contains(&x) && (2..6).contains(&y) {
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
    write(path, o, CT_STORAGE, EXPLICIT_LE);
}

fn render(args: &[&str], input: &Path, out: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "-q", "--size", "32x32"])
        .args(args)
        .arg("-o")
        .arg(out)
        .arg(input)
        .output()
        .unwrap()
}

/// Issue 17: what the DICOM reader assumed reaches the user of `glint render` (as it
/// does with `glint info`) and the image is written; `--strict` refuses the file
/// with one line and writes nothing.
#[test]
fn render_prints_the_geometry_the_reader_assumed() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("frames.dcm");
    write_frames_without_positions(&input);
    let out = dir.path().join("frames.png");
    let run = render(&[], &input, &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("frames.dcm: geometry assumed: no ImagePositionPatient")
            && stderr.contains("SpacingBetweenSlices"),
        "{stderr}"
    );
    // The image: the 32x32 asked for, with the bright block in the middle of the frame
    // and the corners, outside the volume, dark.
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut px = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut px).unwrap();
    assert_eq!((info.width, info.height), (32, 32));
    let channels = info.color_type.samples();
    let at = |x: usize, y: usize| &px[(y * 32 + x) * channels..][..3];
    assert!(
        at(16, 16).iter().any(|&c| c > 40),
        "centre {:?}",
        at(16, 16)
    );
    for (x, y) in [(0, 0), (31, 0), (0, 31), (31, 31)] {
        assert_eq!(at(x, y), [0, 0, 0], "corner ({x}, {y})");
    }

    let strict_out = dir.path().join("strict.png");
    let run = render(&["--strict"], &input, &strict_out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--strict"), "{stderr}");
    assert!(!strict_out.exists());
}

/// An OME-Zarr store streamed into the bricks: a missing chunk is noted on stderr and
/// the image written, `--strict` refuses it; a corrupt chunk (found while the field is
/// built) fails with one line naming the store and writes nothing.
#[test]
fn a_zarr_store_with_a_missing_or_corrupt_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    glint_testkit::copy_dir(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/data/zarr/missing-chunk.zarr"),
        &store,
    );
    let out = dir.path().join("m.png");
    let run = render(&[], &store, &out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("1 of 12 chunks missing"), "{stderr}");
    assert!(out.is_file());

    let strict_out = dir.path().join("strict.png");
    let run = render(&["--strict"], &store, &strict_out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("1 of 12 chunks are missing"), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(!strict_out.exists());

    std::fs::write(store.join("0/1/1/1"), b"not a blosc chunk").unwrap();
    let bad_out = dir.path().join("bad.png");
    let run = render(&[], &store, &bad_out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains("m.zarr: level '0'") && stderr.contains("blosc"),
        "{stderr}"
    );
    assert_eq!(
        stderr
            .lines()
            .filter(|l| l.starts_with("glint: error"))
            .count(),
        1,
        "{stderr}"
    );
    assert!(!bad_out.exists());
}

/// Issue 42: `--environment FILE|NAME` renders a `path` scene; a truncated or
/// malformed `.hdr`, or an unknown name, is one line, a non-zero exit and no image.
#[test]
fn environment_maps_render_and_bad_ones_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("frames.dcm");
    write_frames_without_positions(&input);
    // A 4x2 Radiance file, flat scanlines (the decoder reads widths below 8 so) of
    // RGBE (128, 128, 128, 128): 0.5 everywhere.
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    hdr.extend(std::iter::repeat_n(128u8, 4 * 8));
    let good = dir.path().join("grey.hdr");
    std::fs::write(&good, &hdr).unwrap();
    let truncated = dir.path().join("truncated.hdr");
    std::fs::write(&truncated, &hdr[..hdr.len() - 9]).unwrap();
    let path = ["--lighting", "path", "--spp", "2", "--no-headlight"];
    for map in [good.to_str().unwrap(), "studio"] {
        let out = dir.path().join("ok.png");
        let o = render(&[&path[..], &["--environment", map]].concat(), &input, &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(out.exists());
        std::fs::remove_file(&out).unwrap();
    }
    for (map, want) in [
        (truncated.to_str().unwrap(), "truncated.hdr"),
        ("nowhere", "studio"),
    ] {
        let out = dir.path().join("bad.png");
        let o = render(&[&path[..], &["--environment", map]].concat(), &input, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        // One error line (after the reader's note on the geometry it assumed).
        let errors: Vec<_> = err.lines().filter(|l| l.contains("error")).collect();
        assert_eq!(errors.len(), 1, "{err}");
        assert!(
            errors[0].contains("environment map") && errors[0].contains(want),
            "{err}"
        );
        assert!(!out.exists());
    }
}
