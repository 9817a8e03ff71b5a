//! Symbolic links as DataLad datasets and exports keep files: links followed, a link to
//! nothing named for what it is, in a file and in a DICOM directory.

use std::os::unix::fs::symlink;
use std::path::Path;

use dicom_core::value::PrimitiveValue;
use dicom_core::VR;
use dicom_dictionary_std::tags;
use glint_io::{nifti, Endian, IoError, ReadOptions, Samples, Volume};
use glint_testkit::dicom::{ds, put, ImageHeader, CT_STORAGE, EXPLICIT_LE};

/// Writes a 2 x 2 CT slice at `z` of series 1.2.3.9 to `path`.
fn slice(path: &Path, z: f64, k: u32) {
    let mut o = ImageHeader {
        instance: format!("1.2.3.9.{k}"),
        series: "1.2.3.9".into(),
        ..ImageHeader::ct(2, 2)
    }
    .object();
    put(&mut o, tags::PIXEL_SPACING, VR::DS, ds(&[1.0, 1.0]));
    put(
        &mut o,
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        ds(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
    );
    put(
        &mut o,
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        ds(&[0.0, 0.0, z]),
    );
    let px: Vec<u16> = vec![k as u16; 4];
    put(
        &mut o,
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(px.into()),
    );
    glint_testkit::dicom::write(path, o, CT_STORAGE, EXPLICIT_LE);
}

#[test]
fn a_file_reached_through_a_link_reads_and_a_link_to_nothing_says_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    let vol = Volume::new([2, 2, 2], [1.0; 3], Samples::U8((0..8).collect())).unwrap();
    let object = root.join(".git/annex/objects/aa/bb/KEY.nii/KEY.nii");
    std::fs::create_dir_all(object.parent().unwrap()).unwrap();
    nifti::write(&object, &vol, false, Endian::Little).unwrap();
    symlink(
        ".git/annex/objects/aa/bb/KEY.nii/KEY.nii",
        root.join("t1.nii"),
    )
    .unwrap();
    symlink(
        ".git/annex/objects/cc/dd/KEY2.nii/KEY2.nii",
        root.join("t2.nii"),
    )
    .unwrap();
    symlink("/no/such/file.stl", root.join("mesh.stl")).unwrap();

    let back = glint_io::read_volume(&root.join("t1.nii"), &ReadOptions::default()).unwrap();
    assert_eq!(back.samples, vol.samples);
    let t2 = root.join("t2.nii");
    let e = glint_io::read_volume(&t2, &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, IoError::AnnexMissing { .. }), "{e}");
    let line = glint_io::one_line(&e);
    assert_eq!(
        line,
        format!(
            "{}: content not present (git-annex): run `datalad get {}`",
            t2.display(),
            t2.display()
        )
    );
    let e = glint_io::read_mesh(&root.join("mesh.stl")).unwrap_err();
    assert_eq!(
        glint_io::one_line(&e),
        format!(
            "{}: broken symbolic link to /no/such/file.stl",
            root.join("mesh.stl").display()
        )
    );
}

/// A DICOM directory of links reads through them; one slice never fetched is an error
/// that names it (a missing slice must not go unnoticed), and the listing names it.
#[test]
fn a_dicom_directory_of_links() {
    let store = tempfile::tempdir().unwrap();
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        let object = store.path().join(format!("obj{k}"));
        slice(&object, 2.0 * k as f64, k);
        symlink(&object, dir.path().join(format!("s{k}.dcm"))).unwrap();
    }
    let v = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, [2, 2, 3]);

    let gone = dir.path().join("s3.dcm");
    symlink("../../.git/annex/objects/x/y/KEY/KEY", &gone).unwrap();
    let e = glint_io::read_volume(dir.path(), &ReadOptions::default()).unwrap_err();
    assert!(matches!(e, IoError::AnnexMissing { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("s3.dcm: content not present (git-annex)"),
        "{e}"
    );
    let listing = glint_io::dicom::list(dir.path(), &ReadOptions::default()).unwrap();
    assert_eq!(listing.series.len(), 1);
    assert_eq!(listing.series[0].slices, 3);
    assert_eq!(listing.skipped.len(), 1);
    assert_eq!(listing.skipped[0].path, gone);
    assert!(
        listing.skipped[0].reason.contains("run `datalad get"),
        "{}",
        listing.skipped[0].reason
    );
}
