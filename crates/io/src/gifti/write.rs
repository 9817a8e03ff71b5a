//! Writing GIFTI surfaces.

use std::io::Write;
use std::path::Path;

use base64::Engine;

use super::Encoding;
use crate::common::write_atomic;
use crate::{IoError, Mesh};

/// Writes a GIFTI surface (POINTSET in NIFTI_XFORM_UNKNOWN space, TRIANGLE, and
/// normals and scalars when present) with the given encoding; gzip-compresses the whole
/// file when the name ends in `.gz`.
pub fn write(path: &Path, mesh: &Mesh, encoding: Encoding) -> Result<(), IoError> {
    let mut xml = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <!DOCTYPE GIFTI SYSTEM \"http://gifti.projects.nitrc.org/gifti.dtd\">\n",
    );
    let count = 2 + usize::from(mesh.normals.is_some()) + usize::from(mesh.scalars.is_some());
    xml += &format!("<GIFTI Version=\"1.0\" NumberOfDataArrays=\"{count}\">\n");
    let flat = |rows: &[[f32; 3]]| {
        rows.iter()
            .flatten()
            .map(|&x| f64::from(x))
            .collect::<Vec<_>>()
    };
    array(
        &mut xml,
        "NIFTI_INTENT_POINTSET",
        "NIFTI_TYPE_FLOAT32",
        &[mesh.positions.len(), 3],
        &flat(&mesh.positions),
        encoding,
        true,
    );
    let tris: Vec<f64> = mesh
        .triangles
        .iter()
        .flatten()
        .map(|&i| f64::from(i))
        .collect();
    array(
        &mut xml,
        "NIFTI_INTENT_TRIANGLE",
        "NIFTI_TYPE_INT32",
        &[mesh.triangles.len(), 3],
        &tris,
        encoding,
        false,
    );
    if let Some(n) = &mesh.normals {
        array(
            &mut xml,
            "NIFTI_INTENT_VECTOR",
            "NIFTI_TYPE_FLOAT32",
            &[n.len(), 3],
            &flat(n),
            encoding,
            false,
        );
    }
    if let Some(s) = &mesh.scalars {
        let v: Vec<f64> = s.iter().map(|&x| f64::from(x)).collect();
        array(
            &mut xml,
            "NIFTI_INTENT_SHAPE",
            "NIFTI_TYPE_FLOAT32",
            &[s.len()],
            &v,
            encoding,
            false,
        );
    }
    xml += "</GIFTI>\n";
    let gz = path.to_string_lossy().to_ascii_lowercase().ends_with(".gz");
    write_atomic(path, |w| {
        if gz {
            let mut e = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            e.write_all(xml.as_bytes())?;
            e.finish()?;
            Ok(())
        } else {
            w.write_all(xml.as_bytes())
        }
    })
}

fn array(
    xml: &mut String,
    intent: &str,
    data_type: &str,
    dims: &[usize],
    v: &[f64],
    encoding: Encoding,
    coordinates: bool,
) {
    let enc = match encoding {
        Encoding::Ascii => "ASCII",
        Encoding::Base64 => "Base64Binary",
        Encoding::GzipBase64 => "GZipBase64Binary",
    };
    xml.push_str(&format!(
        "  <DataArray Intent=\"{intent}\" DataType=\"{data_type}\" \
         ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"{}\"",
        dims.len()
    ));
    for (i, d) in dims.iter().enumerate() {
        xml.push_str(&format!(" Dim{i}=\"{d}\""));
    }
    xml.push_str(&format!(
        " Encoding=\"{enc}\" Endian=\"LittleEndian\" ExternalFileName=\"\" ExternalFileOffset=\"\">\n"
    ));
    if coordinates {
        xml.push_str(
            "    <CoordinateSystemTransformMatrix>\n\
             <DataSpace><![CDATA[NIFTI_XFORM_UNKNOWN]]></DataSpace>\n\
             <TransformedSpace><![CDATA[NIFTI_XFORM_UNKNOWN]]></TransformedSpace>\n\
             <MatrixData>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</MatrixData>\n\
             </CoordinateSystemTransformMatrix>\n",
        );
    }
    let int = data_type == "NIFTI_TYPE_INT32";
    let data = match encoding {
        Encoding::Ascii => v
            .iter()
            .map(|x| {
                if int {
                    format!("{}", *x as i64)
                } else {
                    format!("{}", *x as f32)
                }
            })
            .collect::<Vec<_>>()
            .join(" "),
        _ => {
            let bytes: Vec<u8> = v
                .iter()
                .flat_map(|&x| {
                    if int {
                        (x as i32).to_le_bytes()
                    } else {
                        (x as f32).to_le_bytes()
                    }
                })
                .collect();
            let bytes = if encoding == Encoding::GzipBase64 {
                let mut e =
                    flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
                e.write_all(&bytes).expect("writing to a Vec cannot fail");
                e.finish().expect("writing to a Vec cannot fail")
            } else {
                bytes
            };
            base64::engine::general_purpose::STANDARD.encode(bytes)
        }
    };
    xml.push_str("    <Data>");
    xml.push_str(&data);
    xml.push_str("</Data>\n  </DataArray>\n");
}
