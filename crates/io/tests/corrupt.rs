//! Corrupted files never panic: valid files of every writable format, truncated at a
//! random length or with random bytes overwritten, must read as `Ok` or a typed `Err`.

use std::path::{Path, PathBuf};

use glint_io::{gifti, mesh, nifti, nrrd, Endian, Mesh, ReadOptions, Samples, Volume};
use proptest::prelude::*;

/// Writes one fixture file.
type Writer<'a> = Box<dyn Fn(&Path) + 'a>;

/// One valid file per format, written once into a directory that lives for the test.
fn originals(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut vol = Volume::new([5, 4, 3], [1.0; 3], Samples::I16((0..60).collect())).unwrap();
    vol.affine[0][3] = -3.0;
    let tri = Mesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        normals: None,
        scalars: Some(vec![1.0, 2.0, 3.0, 4.0]),
    };
    let files: Vec<(&str, Writer)> = vec![
        (
            "a.nii",
            Box::new(|p| nifti::write(p, &vol, false, Endian::Big).unwrap()),
        ),
        (
            "b.nii.gz",
            Box::new(|p| nifti::write(p, &vol, true, Endian::Little).unwrap()),
        ),
        (
            "c.nrrd",
            Box::new(|p| nrrd::write(p, &vol, nrrd::Encoding::Raw, Endian::Little).unwrap()),
        ),
        (
            "d.nrrd",
            Box::new(|p| nrrd::write(p, &vol, nrrd::Encoding::Gzip, Endian::Big).unwrap()),
        ),
        ("e.stl", Box::new(|p| mesh::write_stl(p, &tri).unwrap())),
        ("f.obj", Box::new(|p| mesh::write_obj(p, &tri).unwrap())),
        (
            "g.ply",
            Box::new(|p| mesh::write_ply(p, &tri, mesh::PlyEncoding::Ascii).unwrap()),
        ),
        (
            "h.ply",
            Box::new(|p| mesh::write_ply(p, &tri, mesh::PlyEncoding::BinaryLittleEndian).unwrap()),
        ),
        (
            "i.gii",
            Box::new(|p| gifti::write(p, &tri, gifti::Encoding::Ascii).unwrap()),
        ),
        (
            "j.gii",
            Box::new(|p| gifti::write(p, &tri, gifti::Encoding::GzipBase64).unwrap()),
        ),
        ("k.dcm", Box::new(write_dicom)),
        // MGH has no writer: nibabel's fixtures, plain and gzip-compressed.
        ("l.mgh", Box::new(|p| copy_fixture("mgh/i16.mgh", p))),
        ("m.mgz", Box::new(|p| copy_fixture("mgh/frames.mgz", p))),
    ];
    files
        .into_iter()
        .map(|(name, write)| {
            let p = dir.join(name);
            write(&p);
            let bytes = std::fs::read(&p).unwrap();
            (p, bytes)
        })
        .collect()
}

fn copy_fixture(name: &str, to: &Path) {
    let from = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    std::fs::copy(from, to).unwrap();
}

/// A 3x2 CT slice, explicit VR little endian.
fn write_dicom(p: &Path) {
    use dicom_core::value::PrimitiveValue;
    use dicom_core::{dicom_value, DataElement, VR};
    use dicom_dictionary_std::tags;
    use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
    let mut o = InMemDicomObject::new_empty();
    let mut put = |tag, vr, v: PrimitiveValue| {
        o.put(DataElement::new(tag, vr, v));
    };
    put(
        tags::SOP_CLASS_UID,
        VR::UI,
        dicom_value!(Str, "1.2.840.10008.5.1.4.1.1.2"),
    );
    put(
        tags::SOP_INSTANCE_UID,
        VR::UI,
        dicom_value!(Str, "1.2.3.4.5"),
    );
    put(
        tags::SERIES_INSTANCE_UID,
        VR::UI,
        dicom_value!(Str, "1.2.3.4"),
    );
    put(tags::MODALITY, VR::CS, dicom_value!(Str, "CT"));
    put(tags::ROWS, VR::US, dicom_value!(U16, [2]));
    put(tags::COLUMNS, VR::US, dicom_value!(U16, [3]));
    put(tags::BITS_ALLOCATED, VR::US, dicom_value!(U16, [16]));
    put(tags::BITS_STORED, VR::US, dicom_value!(U16, [12]));
    put(tags::PIXEL_REPRESENTATION, VR::US, dicom_value!(U16, [1]));
    put(
        tags::IMAGE_POSITION_PATIENT,
        VR::DS,
        dicom_value!(Strs, ["1", "2", "3"]),
    );
    put(
        tags::IMAGE_ORIENTATION_PATIENT,
        VR::DS,
        dicom_value!(Strs, ["1", "0", "0", "0", "1", "0"]),
    );
    put(
        tags::PIXEL_SPACING,
        VR::DS,
        dicom_value!(Strs, ["0.5", "0.5"]),
    );
    put(tags::RESCALE_INTERCEPT, VR::DS, dicom_value!(Str, "-1024"));
    put(
        tags::PIXEL_DATA,
        VR::OW,
        PrimitiveValue::U16(vec![1, 2, 3, 4, 5, 6].into()),
    );
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax("1.2.840.10008.1.2.1")
        .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.2");
    o.with_meta(meta).unwrap().write_to_file(p).unwrap();
}

fn read_any(p: &Path) {
    let options = ReadOptions {
        max_voxels: 1 << 20,
        ..ReadOptions::default()
    };
    let is_mesh = glint_io::Format::guess(p).is_some_and(glint_io::Format::is_mesh);
    if is_mesh {
        if let Ok(m) = glint_io::read_mesh(p) {
            // Whatever was accepted is consistent.
            assert!(m.validate().is_ok(), "{p:?}");
        }
    } else if let Ok(v) = glint_io::read_volume(p, &options) {
        assert_eq!(v.len(), v.dims.iter().product::<usize>(), "{p:?}");
    }
}

proptest! {
    // 48 cases by default (a fraction of a second); PROPTEST_CASES=5000 for a longer hunt.
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(48)
    ))]

    #[test]
    fn truncated_or_mutated_files_do_not_panic(
        which in 0usize..13,
        cut in 0.0f64..1.0,
        edits in proptest::collection::vec((0.0f64..1.0, any::<u8>()), 0..8),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let files = originals(dir.path());
        let (path, bytes) = &files[which];
        let mut b = bytes.clone();
        for (at, v) in &edits {
            let i = ((b.len() - 1) as f64 * at) as usize;
            b[i] = *v;
        }
        if edits.is_empty() {
            b.truncate((b.len() as f64 * cut) as usize);
        }
        std::fs::write(path, &b).unwrap();
        read_any(path);
    }
}
