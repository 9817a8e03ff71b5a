//! Surfaces: STL, OBJ, PLY, GIFTI round trips, hand-written files, bad input, and the
//! fsaverage5 sample.

mod common;

use std::path::PathBuf;

use glint_io::gifti::{self, Encoding};
use glint_io::mesh::{self, PlyEncoding};
use glint_io::{Format, IoError, Mesh};

/// A tetrahedron with outward counter-clockwise faces, normals and scalars.
fn tetra() -> Mesh {
    Mesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.5, 0.0, 0.0],
            [0.0, 2.25, 0.0],
            [0.0, 0.0, -3.125],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        normals: Some(vec![
            [-0.5, -0.5, 0.5],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
        ]),
        scalars: Some(vec![0.25, -1.0, 7.5, 1e-3]),
    }
}

fn file(dir: &tempfile::TempDir, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Triangles as corner coordinates, sorted: equal for meshes that differ only in vertex
/// numbering (STL merges corners in its own order).
fn corner_set(m: &Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut v: Vec<_> = m
        .triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize].map(f32::to_bits)))
        .collect();
    v.sort();
    v
}

#[test]
fn stl_binary_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.stl");
    mesh::write_stl(&p, &tetra()).unwrap();
    // 84-byte header + 50 bytes per triangle.
    assert_eq!(std::fs::metadata(&p).unwrap().len(), 84 + 50 * 4);
    let f = glint_io::open_mesh(&p).unwrap();
    assert_eq!(f.format, Format::Stl);
    assert_eq!(f.mesh.positions.len(), 4);
    assert_eq!(corner_set(&f.mesh), corner_set(&tetra()));
}

#[test]
fn stl_ascii_hand_written() {
    let dir = tempfile::tempdir().unwrap();
    let text = "solid square\n\
        facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 1 1 0\n endloop\nendfacet\n\
        facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 1 0\n  vertex 0 1 0\n endloop\nendfacet\n\
        endsolid square\n";
    let m = glint_io::read_mesh(&file(&dir, "sq.STL", text)).unwrap();
    // Two triangles sharing the diagonal: 4 distinct corners.
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(m.bounds(), Some(([0.0, 0.0, 0.0], [1.0, 1.0, 0.0])));
}

#[test]
fn obj_round_trip_with_normals() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.obj");
    mesh::write_obj(&p, &tetra()).unwrap();
    let m = glint_io::read_mesh(&p).unwrap();
    let want = tetra();
    // tobj numbers vertices in order of first use by a face, so compare by position.
    assert_eq!(m.positions.len(), 4);
    assert_eq!(corner_set(&m), corner_set(&want));
    let normals = m.normals.as_ref().expect("normals kept");
    for (p, n) in m.positions.iter().zip(normals) {
        let i = want.positions.iter().position(|q| q == p).unwrap();
        assert_eq!(*n, want.normals.as_ref().unwrap()[i]);
    }
}

#[test]
fn obj_quads_and_two_objects() {
    let dir = tempfile::tempdir().unwrap();
    let text = "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
                o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n";
    let m = glint_io::read_mesh(&file(&dir, "q.obj", text)).unwrap();
    // The quad becomes 2 triangles, plus 1: 3 triangles over 7 vertices.
    assert_eq!(m.positions.len(), 7);
    assert_eq!(m.triangles.len(), 3);
    assert_eq!(m.bounds(), Some(([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])));
    assert!(m.validate().is_ok());
}

#[test]
fn ply_round_trip_all_encodings() {
    let dir = tempfile::tempdir().unwrap();
    for enc in [
        PlyEncoding::Ascii,
        PlyEncoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian,
    ] {
        let p = dir.path().join(format!("{enc:?}.ply"));
        mesh::write_ply(&p, &tetra(), enc).unwrap();
        let m = glint_io::read_mesh(&p).unwrap();
        assert_eq!(m, tetra(), "{enc:?}");
    }
}

#[test]
fn ply_hand_written_binary_big_endian_with_quad() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\n\
        property double x\nproperty double y\nproperty double z\n\
        element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for p in [
        [0.0f64, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 3.0, 0.0],
        [0.0, 3.0, 0.0],
    ] {
        for x in p {
            bytes.extend_from_slice(&x.to_be_bytes());
        }
    }
    bytes.push(4);
    for i in [0i32, 1, 2, 3] {
        bytes.extend_from_slice(&i.to_be_bytes());
    }
    let m = glint_io::read_mesh(&file(&dir, "q.ply", bytes)).unwrap();
    assert_eq!(m.positions[2], [2.0, 3.0, 0.0]);
    // A fan from vertex 0: (0,1,2) and (0,2,3).
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn gifti_round_trip_all_encodings_plain_and_gzipped() {
    let dir = tempfile::tempdir().unwrap();
    for enc in [Encoding::Ascii, Encoding::Base64, Encoding::GzipBase64] {
        for gz in ["", ".gz"] {
            let p = dir.path().join(format!("{enc:?}.gii{gz}"));
            gifti::write(&p, &tetra(), enc).unwrap();
            let f = glint_io::open_mesh(&p).unwrap();
            assert_eq!(f.mesh, tetra(), "{p:?}");
            assert_eq!(f.format, Format::Gifti);
            assert!(f.coordinate_system.unwrap().contains("NIFTI_XFORM_UNKNOWN"));
        }
    }
}

/// A GIFTI document with the given POINTSET and TRIANGLE arrays (attributes and data).
fn gifti_doc(points: (&str, &str), tris: (&str, &str)) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<GIFTI Version=\"1.0\" NumberOfDataArrays=\"2\">\n\
         <DataArray Intent=\"NIFTI_INTENT_POINTSET\" DataType=\"NIFTI_TYPE_FLOAT32\" {}>\n\
         <CoordinateSystemTransformMatrix><DataSpace>NIFTI_XFORM_UNKNOWN</DataSpace>\
         <TransformedSpace>NIFTI_XFORM_MNI_152</TransformedSpace>\
         <MatrixData>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</MatrixData></CoordinateSystemTransformMatrix>\n\
         <Data>{}</Data></DataArray>\n\
         <DataArray Intent=\"NIFTI_INTENT_TRIANGLE\" DataType=\"NIFTI_TYPE_INT32\" {}>\n\
         <Data>{}</Data></DataArray>\n</GIFTI>\n",
        points.0, points.1, tris.0, tris.1
    )
}

const ASCII_ROW: &str =
    "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"3\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";

#[test]
fn gifti_column_major_ascii() {
    // Column-major: all x, then all y, then all z.
    let dir = tempfile::tempdir().unwrap();
    let cm = "ArrayIndexingOrder=\"ColumnMajorOrder\" Dimensionality=\"2\" Dim0=\"3\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    let doc = gifti_doc((cm, "1 2 3  4 5 6  7 8 9"), (tri, "0 1 2"));
    let f = glint_io::open_mesh(&file(&dir, "cm.gii", doc)).unwrap();
    assert_eq!(
        f.mesh.positions,
        vec![[1.0, 4.0, 7.0], [2.0, 5.0, 8.0], [3.0, 6.0, 9.0]]
    );
    assert_eq!(f.mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(
        f.coordinate_system.as_deref(),
        Some("NIFTI_XFORM_UNKNOWN -> NIFTI_XFORM_MNI_152 (identity)")
    );
}

fn expect_err(dir: &tempfile::TempDir, name: &str, bytes: impl AsRef<[u8]>) -> IoError {
    let p = file(dir, name, bytes);
    let err = glint_io::read_mesh(&p).unwrap_err();
    assert!(
        err.to_string().contains(name),
        "error does not name the file: {err}"
    );
    err
}

#[test]
fn out_of_range_indices_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("bad.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec()),
        (
            "bad.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
              0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"
                .to_vec(),
        ),
        ("neg.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
              0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"
                .to_vec()),
        ("bad.gii", gifti_doc((ASCII_ROW, "0 0 0 1 0 0 0 1 0"), (tri, "0 1 3")).into_bytes()),
        ("neg.gii", gifti_doc((ASCII_ROW, "0 0 0 1 0 0 0 1 0"), (tri, "0 -1 2")).into_bytes()),
    ];
    for (name, bytes) in cases {
        let err = expect_err(&dir, name, bytes);
        assert!(matches!(err, IoError::BadIndex { .. }), "{name}: {err}");
    }
}

#[test]
fn stl_truncated_and_size_mismatch() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("full.stl");
    mesh::write_stl(&p, &tetra()).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let err = expect_err(&dir, "cut.stl", &bytes[..bytes.len() - 20]);
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    let err = expect_err(&dir, "tiny.stl", &bytes[..40]);
    assert!(matches!(err, IoError::Truncated { .. }), "{err}");
    // ASCII that stops inside a facet.
    let err = expect_err(
        &dir,
        "cut_ascii.stl",
        "solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n",
    );
    assert!(
        matches!(err, IoError::Invalid { .. } | IoError::Truncated { .. }),
        "{err}"
    );
}

#[test]
fn wrong_magic() {
    let dir = tempfile::tempdir().unwrap();
    let err = expect_err(&dir, "nope.ply", "PLY?\nformat ascii 1.0\nend_header\n");
    assert!(
        matches!(err, IoError::BadMagic { .. } | IoError::Invalid { .. }),
        "{err}"
    );
    let err = expect_err(&dir, "nope.gii", "<?xml version=\"1.0\"?><html></html>");
    assert!(matches!(err, IoError::BadMagic { .. }), "{err}");
    let err = expect_err(&dir, "nope2.gii", "this is not xml < at all &");
    assert!(
        matches!(err, IoError::BadMagic { .. } | IoError::Invalid { .. }),
        "{err}"
    );
}

#[test]
fn gifti_size_mismatch_and_unsupported() {
    let dir = tempfile::tempdir().unwrap();
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    // 9 values announced, 8 given.
    let err = expect_err(
        &dir,
        "short.gii",
        gifti_doc((ASCII_ROW, "0 0 0 1 0 0 0 1"), (tri, "0 1 2")),
    );
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    // Base64 of 8 bytes for a 3x3 float32 array (36 bytes).
    let b64 = ASCII_ROW.replace("\"ASCII\"", "\"Base64Binary\"");
    let err = expect_err(
        &dir,
        "short64.gii",
        gifti_doc((&b64, "AAAAAAAAAAA="), (tri, "0 1 2")),
    );
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    let ext = ASCII_ROW.replace("\"ASCII\"", "\"ExternalFileBinary\"");
    // External files are read now (tests/gifti.rs), but this one names no file.
    let err = expect_err(&dir, "ext.gii", gifti_doc((&ext, ""), (tri, "0 1 2")));
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
    let f64t = gifti_doc((ASCII_ROW, "0 0 0 1 0 0 0 1 0"), (tri, "0 1 2")).replacen(
        "NIFTI_TYPE_FLOAT32",
        "NIFTI_TYPE_COMPLEX64",
        1,
    );
    let err = expect_err(&dir, "cplx.gii", f64t);
    assert!(matches!(err, IoError::Unsupported { .. }), "{err}");
}

#[test]
fn fsaverage5_pial_left() {
    let Some(path) = common::sample("fsaverage5_pial_left.gii.gz") else {
        return;
    };
    let f = glint_io::open_mesh(&path).unwrap();
    // Counts and bounds computed with Python (base64 + zlib + struct) from the same file:
    // 10242 vertices, 20480 triangles, first triangle (0, 2564, 2562).
    assert_eq!(f.mesh.positions.len(), 10242);
    assert_eq!(f.mesh.triangles.len(), 20480);
    assert_eq!(f.mesh.triangles[0], [0, 2564, 2562]);
    let p0 = f.mesh.positions[0];
    let want0 = [-38.735_96_f64, -19.343_365, 67.220_14];
    assert!(
        (0..3).all(|a| (f64::from(p0[a]) - want0[a]).abs() < 1e-4),
        "{p0:?}"
    );
    let (lo, hi) = f.mesh.bounds().unwrap();
    let want_lo = [-68.788_8_f32, -104.692, -48.324_4];
    let want_hi = [1.221_56_f32, 68.947_4, 78.124];
    for a in 0..3 {
        assert!(
            (lo[a] - want_lo[a]).abs() < 1e-3 && (hi[a] - want_hi[a]).abs() < 1e-3,
            "{lo:?} {hi:?}"
        );
    }
    assert_eq!(
        f.coordinate_system.as_deref(),
        Some("NIFTI_XFORM_UNKNOWN -> NIFTI_XFORM_TALAIRACH (identity)")
    );
    assert!(f.mesh.validate().is_ok());
}

#[test]
fn fsaverage5_sulcal_depth_is_not_a_surface() {
    let Some(path) = common::sample("fsaverage5_sulc_left.gii.gz") else {
        return;
    };
    let err = glint_io::read_mesh(&path).unwrap_err();
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
    assert!(err.to_string().contains("NIFTI_INTENT_SHAPE"), "{err}");
}

/// A binary STL of one triangle with the given corners.
fn stl_binary(corners: [[f32; 3]; 3]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend(1u32.to_le_bytes());
    b.extend([0u8; 12]);
    for c in corners {
        for x in c {
            b.extend(x.to_le_bytes());
        }
    }
    b.extend([0u8; 2]);
    b
}

/// Review defect 5: non-finite positions and normals are refused by every mesh format
/// (binary STL and OBJ used to accept them and report infinite bounds).
#[test]
fn non_finite_vertices_refused_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let ply_head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
        property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    let cases: Vec<(&str, Vec<u8>)> = vec![
        (
            "nan.stl",
            stl_binary([[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        ),
        (
            "inf.stl",
            stl_binary([[0.0, 0.0, 0.0], [f32::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        ),
        (
            "nan.obj",
            b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "nrm.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nf 1//1 2//1 3//1\n".to_vec(),
        ),
        ("nan.ply", {
            // Binary: ASCII PLY has no spelling of NaN that ply-rs parses.
            let mut b = ply_head
                .replace("ascii", "binary_little_endian")
                .into_bytes();
            for x in [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0f32] {
                b.extend(x.to_le_bytes());
            }
            b.push(3);
            for i in [0i32, 1, 2] {
                b.extend(i.to_le_bytes());
            }
            b
        }),
        (
            "inf.gii",
            gifti_doc((ASCII_ROW, "0 0 0 inf 0 0 0 1 0"), (tri, "0 1 2")).into_bytes(),
        ),
    ];
    for (name, bytes) in cases {
        let err = expect_err(&dir, name, bytes);
        assert!(
            matches!(err, IoError::Invalid { .. }) && err.to_string().contains("non-finite"),
            "{name}: {err}"
        );
    }
    let mut m = tetra();
    m.normals.as_mut().unwrap()[2][1] = f32::NAN;
    assert!(matches!(m.validate(), Err(IoError::Inconsistent(_))));
    let p = dir.path().join("out.stl");
    assert!(mesh::write_stl(&p, &m).is_err());
    assert!(!p.exists());
}

/// Review defect 3: a small gzipped GIFTI inflating to far more XML than its arrays can
/// hold (a decompression bomb) is refused without inflating it all, and `<Data>` text
/// beyond what the dimensions announce is refused instead of being copied.
#[test]
fn gifti_decompression_bomb_and_oversized_data() {
    let dir = tempfile::tempdir().unwrap();
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    // 80 MB of blanks after nine numbers: valid XML, about 80 kB gzipped (ratio ~1000).
    let pad = " ".repeat(80 << 20);
    let doc = gifti_doc(
        (ASCII_ROW, &format!("0 0 0 1 0 0 0 1 0{pad}")),
        (tri, "0 1 2"),
    );
    let gz = common::gzip(doc.as_bytes());
    assert!(gz.len() < 1 << 20);
    let err = expect_err(&dir, "bomb.gii.gz", gz);
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
    // Uncompressed: 200 kB of blanks in the Data of a 3x3 array.
    let pad = " ".repeat(200_000);
    let doc = gifti_doc(
        (ASCII_ROW, &format!("0 0 0 1 0 0 0 1 0{pad}")),
        (tri, "0 1 2"),
    );
    let err = expect_err(&dir, "padded.gii", doc);
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    // Modest padding is fine.
    let doc = gifti_doc((ASCII_ROW, "\n 0 0 0\n 1 0 0\n 0 1 0\n"), (tri, "0 1 2"));
    let f = glint_io::open_mesh(&file(&dir, "ok.gii", doc)).unwrap();
    assert_eq!(f.mesh.positions.len(), 3);
}

/// Review defect 10: a one-dimensional VECTOR array is not per-vertex normals; it used
/// to fail the whole read, now it is skipped.
#[test]
fn gifti_one_dimensional_vector_array_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let tri = "ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\"";
    let vec1 = "<DataArray Intent=\"NIFTI_INTENT_VECTOR\" DataType=\"NIFTI_TYPE_FLOAT32\" \
        ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"1\" Dim0=\"3\" Encoding=\"ASCII\" \
        Endian=\"LittleEndian\"><Data>1 2 3</Data></DataArray>\n</GIFTI>";
    let doc = gifti_doc((ASCII_ROW, "0 0 0 1 0 0 0 1 0"), (tri, "0 1 2"))
        .replace("NumberOfDataArrays=\"2\"", "NumberOfDataArrays=\"3\"")
        .replace("</GIFTI>", vec1);
    let f = glint_io::open_mesh(&file(&dir, "vec1.gii", doc)).unwrap();
    assert_eq!(f.mesh.positions.len(), 3);
    assert_eq!(f.mesh.triangles, vec![[0, 1, 2]]);
    assert!(f.mesh.normals.is_none());
}

/// Issue 17: a binary PLY header declaring `element face` twice, the second with
/// 1,000,000,000 faces and no data, aborted on a 4.5 GB allocation. Now refused before
/// any allocation: the duplicate name, and (without it) the counts the file cannot hold.
#[test]
fn ply_duplicate_element_with_a_billion_faces_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\n\
        property list uchar int vertex_indices\n";
    let mut bytes = format!(
        "{head}element face 1000000000\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bytes.extend(v.to_le_bytes());
    }
    let err = expect_err(&dir, "twice.ply", &bytes);
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
    assert!(err.to_string().contains("declared twice"), "{err}");
    // One face element of a billion faces: each takes at least its 1-byte list count,
    // which the 36 bytes after the header cannot hold.
    let mut bytes =
        format!("{head}end_header\n").replace("element face 1\n", "element face 1000000000\n");
    let mut bytes = std::mem::take(&mut bytes).into_bytes();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bytes.extend(v.to_le_bytes());
    }
    let err = expect_err(&dir, "billion.ply", &bytes);
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
    assert!(err.to_string().contains("1000000000 'face'"), "{err}");
    // ASCII: at least two characters a value.
    let err = expect_err(
        &dir,
        "billion_ascii.ply",
        "ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\n\
         property float y\nproperty float z\nend_header\n0 0 0\n",
    );
    assert!(matches!(err, IoError::SizeMismatch { .. }), "{err}");
}

/// Every PLY error is one line, whatever the parser quotes.
#[test]
fn ply_errors_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let err = expect_err(
        &dir,
        "badline.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nend_header\n0 0 0\n1 zero 2 3 4 5 6\n0 0 0\n",
    );
    let msg = err.to_string();
    assert!(!msg.contains('\n'), "{msg:?}");
    assert!(matches!(err, IoError::Invalid { .. }), "{err}");
}

/// The scalar of a PLY vertex is taken by name preference (`scalar` before `quality`),
/// properties of other types are converted, and unknown ones ignored.
#[test]
fn ply_typed_reader_properties() {
    let dir = tempfile::tempdir().unwrap();
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty short x\nproperty uchar y\n\
        property double z\nproperty float quality\nproperty uchar red\nproperty float scalar\n\
        element face 1\nproperty list uchar int vertex_index\nend_header\n\
        -1 2 0.5 9 255 0.25\n3 4 1.5 9 0 0.5\n5 6 2.5 9 7 0.75\n3 0 1 2\n";
    let m = glint_io::read_mesh(&file(&dir, "typed.ply", text)).unwrap();
    assert_eq!(
        m.positions,
        vec![[-1.0, 2.0, 0.5], [3.0, 4.0, 1.5], [5.0, 6.0, 2.5]]
    );
    assert_eq!(m.scalars, Some(vec![0.25, 0.5, 0.75]));
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    assert!(m.normals.is_none());
}
