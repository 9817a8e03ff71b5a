//! GIFTI overlays, legacy encodings, external-file arrays and one-line errors (issue 17).

mod common;

use std::path::PathBuf;

use glint_io::{read_surface_data, IoError, VertexValues};

fn file(dir: &tempfile::TempDir, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A DataArray element (attributes, then data) in a GIFTI document.
fn array(intent: &str, ty: &str, dims: &[usize], enc: &str, extra: &str, data: &str) -> String {
    let mut a = format!(
        "<DataArray Intent=\"{intent}\" DataType=\"{ty}\" ArrayIndexingOrder=\"RowMajorOrder\" \
         Dimensionality=\"{}\" Encoding=\"{enc}\" Endian=\"LittleEndian\" {extra}",
        dims.len()
    );
    for (i, d) in dims.iter().enumerate() {
        a += &format!(" Dim{i}=\"{d}\"");
    }
    a + &format!(">\n<Data>{data}</Data></DataArray>\n")
}

fn doc(arrays: &[String], labels: &str) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<GIFTI Version=\"1.0\" \
         NumberOfDataArrays=\"{}\">\n{labels}{}</GIFTI>\n",
        arrays.len(),
        arrays.concat()
    )
}

const F32: &str = "NIFTI_TYPE_FLOAT32";
const I32: &str = "NIFTI_TYPE_INT32";
/// 3x3 float32 little-endian 0 0 0 1 0 0 0 1 0, base64 (Python: struct.pack('<9f', ...)).
const POINTS_B64: &str = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
/// int32 little-endian 0 1 2, base64.
const TRI_B64: &str = "AAAAAAEAAAACAAAA";

#[test]
fn legacy_b64bin_encoding_is_base64() {
    let dir = tempfile::tempdir().unwrap();
    let enc = "GIFTI_ENCODING_B64BIN";
    let d = doc(
        &[
            array("NIFTI_INTENT_POINTSET", F32, &[3, 3], enc, "", POINTS_B64),
            array("NIFTI_INTENT_TRIANGLE", I32, &[1, 3], enc, "", TRI_B64),
        ],
        "",
    );
    let m = glint_io::read_mesh(&file(&dir, "b64bin.gii", d)).unwrap();
    assert_eq!(
        m.positions,
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
}

fn le_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn external_file_beside_the_gifti_is_read() {
    let dir = tempfile::tempdir().unwrap();
    // 5 junk bytes, then the points, then the triangle.
    let mut bin = vec![9u8; 5];
    bin.extend(le_bytes(&[0., 0., 0., 1., 0., 0., 0., 1., 0.]));
    bin.extend([0i32, 1, 2].iter().flat_map(|x| x.to_le_bytes()));
    file(&dir, "surf.dat", &bin);
    let ext = |off: usize| format!("ExternalFileName=\"surf.dat\" ExternalFileOffset=\"{off}\"");
    let enc = "ExternalFileBinary";
    let d = doc(
        &[
            array("NIFTI_INTENT_POINTSET", F32, &[3, 3], enc, &ext(5), ""),
            array("NIFTI_INTENT_TRIANGLE", I32, &[1, 3], enc, &ext(41), ""),
        ],
        "",
    );
    let m = glint_io::read_mesh(&file(&dir, "ext.gii", &d)).unwrap();
    assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
    assert_eq!(m.positions[2], [0.0, 1.0, 0.0]);
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    // An offset leaving too few bytes: a size mismatch, not a short read.
    let short = d.replace("ExternalFileOffset=\"41\"", "ExternalFileOffset=\"45\"");
    let err = glint_io::read_mesh(&file(&dir, "short.gii", short)).unwrap_err();
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
}

#[test]
fn external_file_outside_the_directory_is_refused() {
    let outer = tempfile::tempdir().unwrap();
    let secret = outer.path().join("secret.dat");
    std::fs::write(&secret, le_bytes(&[7.0; 9])).unwrap();
    let dir = tempfile::tempdir_in(outer.path()).unwrap();
    std::os::unix::fs::symlink(&secret, dir.path().join("link.dat")).unwrap();
    let enc = "ExternalFileBinary";
    for name in [
        "../secret.dat".to_string(),
        secret.display().to_string(),
        "link.dat".to_string(),
        "./../secret.dat".to_string(),
    ] {
        let ext = format!("ExternalFileName=\"{name}\" ExternalFileOffset=\"0\"");
        let d = doc(&[array("NIFTI_INTENT_SHAPE", F32, &[9], enc, &ext, "")], "");
        let p = file(&dir, "evil.gii", d);
        let err = read_surface_data(&p).unwrap_err();
        assert!(matches!(err, IoError::Unsupported { .. }), "{name}: {err}");
        assert!(err.to_string().contains("own directory"), "{err}");
    }
}

#[test]
fn xml_errors_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    // A broken attribute and a broken closing tag, both quoting text with newlines.
    for (name, text) in [
        (
            "attr.gii",
            "<GIFTI Version=\"1.0\">\n<DataArray Intent=\"a\nb\" Dim0=\"1\n2\n\n\"></DataArray></GIFTI>",
        ),
        ("close.gii", "<GIFTI>\n<DataArray>\n</Data\nArray\n>\n</GIFTI>"),
        (
            "type.gii",
            "<GIFTI><DataArray Intent=\"NIFTI_INTENT_SHAPE\" DataType=\"X\n\nY\" \
             Dimensionality=\"1\" Dim0=\"1\" Encoding=\"ASCII\"><Data>1</Data></DataArray></GIFTI>",
        ),
    ] {
        let err = read_surface_data(&file(&dir, name, text)).unwrap_err();
        let msg = err.to_string();
        assert!(!msg.contains('\n') && !msg.contains('\r'), "{name}: {msg:?}");
    }
}

#[test]
fn label_and_time_series_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let labels = "<LabelTable>\n<Label Key=\"0\" Red=\"1\" Green=\"1\" Blue=\"1\" Alpha=\"0\">\
        <![CDATA[???]]></Label>\n<Label Key=\"7\" Red=\"0.5\" Green=\"0\" Blue=\"0.25\" \
        Alpha=\"1\"><![CDATA[precentral]]></Label>\n</LabelTable>\n";
    let shape = array("NIFTI_INTENT_SHAPE", F32, &[3], "ASCII", "", "0.5 -1 2").replace(
        "<Data>",
        "<MetaData><MD><Name>Name</Name><Value>thickness</Value></MD></MetaData><Data>",
    );
    let d = doc(
        &[
            array(
                "NIFTI_INTENT_POINTSET",
                F32,
                &[3, 3],
                "ASCII",
                "",
                "0 0 0 1 0 0 0 1 0",
            ),
            array("NIFTI_INTENT_TRIANGLE", I32, &[1, 3], "ASCII", "", "0 1 2"),
            shape,
            array("NIFTI_INTENT_LABEL", I32, &[3], "ASCII", "", "7 0 7"),
            // Column-major 3 x 2: the columns (time points) are 1 2 3 and 4 5 6.
            array(
                "NIFTI_INTENT_TIME_SERIES",
                F32,
                &[3, 2],
                "ASCII",
                "",
                "1 2 3 4 5 6",
            )
            .replace("RowMajorOrder", "ColumnMajorOrder"),
            // Not per-vertex (4 values for 3 vertices): skipped.
            array("NIFTI_INTENT_SHAPE", F32, &[4], "ASCII", "", "1 2 3 4"),
        ],
        labels,
    );
    let p = file(&dir, "overlays.gii", d);
    let data = read_surface_data(&p).unwrap();
    let names: Vec<&str> = data.iter().map(|d| d.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "thickness",
            "NIFTI_INTENT_LABEL #3",
            "NIFTI_INTENT_TIME_SERIES #4 [0]",
            "NIFTI_INTENT_TIME_SERIES #4 [1]"
        ]
    );
    assert_eq!(data[0].values, VertexValues::Scalars(vec![0.5, -1.0, 2.0]));
    let VertexValues::Labels { keys, table } = &data[1].values else {
        panic!("{:?}", data[1]);
    };
    assert_eq!(keys, &[7, 0, 7]);
    assert_eq!(table.len(), 2);
    assert_eq!(table[1].key, 7);
    assert_eq!(table[1].name, "precentral");
    assert_eq!(table[1].rgba, [0.5, 0.0, 0.25, 1.0]);
    assert_eq!(data[2].values, VertexValues::Scalars(vec![1.0, 2.0, 3.0]));
    assert_eq!(data[3].values, VertexValues::Scalars(vec![4.0, 5.0, 6.0]));
    // The surface itself still reads, with the first per-vertex array as its scalars.
    let m = glint_io::read_mesh(&p).unwrap();
    assert_eq!(m.scalars, Some(vec![0.5, -1.0, 2.0]));
}

/// fsaverage5 left sulcal depth: a shape-only GIFTI (GZipBase64Binary). Reference
/// values from nibabel 5.4.2 via scripts/fixtures/gifti-reference.py.
#[test]
fn fsaverage5_sulcal_depth_matches_nibabel() {
    let Some(path) = common::sample("fsaverage5_sulc_left.gii.gz") else {
        return;
    };
    let data = read_surface_data(&path).unwrap();
    assert_eq!(data.len(), 1);
    assert_eq!(data[0].intent, "NIFTI_INTENT_SHAPE");
    assert_eq!(
        data[0].name,
        "/home/alexis/freesurfer/subjects/fsaverage5/surf/lh.sulc"
    );
    let VertexValues::Scalars(v) = &data[0].values else {
        panic!("not scalars");
    };
    assert_eq!(v.len(), 10242);
    let first = [
        -0.781268835067749,
        -0.8170627355575562,
        0.5143870115280151,
        0.5151214599609375,
        -0.7543818950653076,
    ];
    for (a, b) in v.iter().zip(first) {
        assert_eq!(f64::from(*a), b);
    }
    assert_eq!(f64::from(v[8268]), 1.8069095611572266);
    assert_eq!(f64::from(v[814]), -1.4937248229980469);
    let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    assert_eq!(
        (f64::from(lo), f64::from(hi)),
        (-1.4937248229980469, 1.8069095611572266)
    );
    let sum: f64 = v.iter().map(|&x| f64::from(x)).sum();
    assert!((sum - 304.6656569574261).abs() < 1e-9, "{sum}");
}
