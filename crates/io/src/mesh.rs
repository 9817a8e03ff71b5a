//! STL (stl_io), OBJ (tobj) and PLY (ply-rs-bw, the maintained fork of ply-rs) surfaces,
//! and the index check every mesh reader ends with.

use std::io::{BufReader, Read, Seek};
use std::path::Path;

use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType as PlyScalar,
};

use crate::common::{open, os_or_invalid, write_atomic};
use crate::{Format, IoError, Mesh, MeshFile};

/// Refuses a mesh whose faces refer to vertices it does not have, whose normals or
/// scalars do not match the vertex count, or whose positions or normals are not finite.
/// Every mesh reader (STL, OBJ, PLY, GIFTI) and writer ends with this check.
pub(crate) fn check_indices(path: &Path, mesh: &Mesh) -> Result<(), IoError> {
    let n = mesh.positions.len();
    if let Some(what) = mesh.non_finite() {
        return Err(IoError::Invalid {
            path: path.into(),
            what,
        });
    }
    if let Some((k, t)) = mesh
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&i| i as usize >= n))
    {
        return Err(IoError::BadIndex {
            path: path.into(),
            what: format!("triangle {k} {t:?} refers past the {n} vertices"),
        });
    }
    if mesh.normals.as_ref().is_some_and(|v| v.len() != n)
        || mesh.scalars.as_ref().is_some_and(|v| v.len() != n)
    {
        return Err(IoError::SizeMismatch {
            path: path.into(),
            what: format!("normals or scalars do not match the {n} vertices"),
        });
    }
    Ok(())
}

fn mesh_file(
    path: &Path,
    mesh: Mesh,
    format: Format,
    notes: Vec<String>,
) -> Result<MeshFile, IoError> {
    check_indices(path, &mesh)?;
    Ok(MeshFile {
        mesh,
        format,
        coordinate_system: None,
        notes,
    })
}

/// Reads an STL file, binary or ASCII (stl_io tells them apart). Identical corner
/// positions are merged into shared vertices; the facet normals are not kept (they are
/// per face, the mesh's normals per vertex).
pub fn read_stl(path: &Path) -> Result<MeshFile, IoError> {
    let mut file = open(path)?;
    let len = file.metadata().map_err(|e| os_or_invalid(path, e))?.len();
    let mut head = Vec::with_capacity(84);
    (&mut file)
        .take(84)
        .read_to_end(&mut head)
        .map_err(|e| os_or_invalid(path, e))?;
    // Binary: an 80-byte header, a u32 triangle count, 50 bytes per triangle. A file of
    // exactly that size is binary even if its header starts with "solid" (some writers
    // do that).
    let count = (head.len() == 84)
        .then(|| u64::from(u32::from_le_bytes([head[80], head[81], head[82], head[83]])));
    let binary = count.is_some_and(|c| len == 84 + 50 * c);
    let ascii = !binary && head.starts_with(b"solid");
    if !binary && !ascii {
        return Err(match count {
            None => IoError::Truncated {
                path: path.into(),
                what: format!("{len} bytes: neither ASCII ('solid ...') nor a binary STL header (84 bytes)"),
            },
            Some(c) => IoError::SizeMismatch {
                path: path.into(),
                what: format!(
                    "the binary header announces {c} triangles ({} bytes), the file has {len} bytes",
                    84 + 50 * c
                ),
            },
        });
    }
    file.rewind().map_err(|e| os_or_invalid(path, e))?;
    let mut reader = BufReader::new(file);
    let indexed = stl_io::read_stl(&mut reader).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => IoError::Truncated {
            path: path.into(),
            what: "the STL ends inside a facet".into(),
        },
        _ => IoError::Invalid {
            path: path.into(),
            what: format!("not a valid STL: {e}"),
        },
    })?;
    let mesh = Mesh {
        positions: indexed.vertices.iter().map(|v| v.0).collect(),
        triangles: indexed
            .faces
            .iter()
            .map(|f| f.vertices.map(|i| i as u32))
            .collect(),
        normals: None,
        scalars: None,
    };
    let note = if ascii { "ASCII STL" } else { "binary STL" };
    mesh_file(path, mesh, Format::Stl, vec![note.into()])
}

/// Writes a binary STL (facet normals from the triangles' corners).
pub fn write_stl(path: &Path, mesh: &Mesh) -> Result<(), IoError> {
    check_indices(path, mesh)?;
    let tris: Vec<stl_io::Triangle> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let n = if len > 0.0 {
                n.map(|x| x / len)
            } else {
                [0.0; 3]
            };
            stl_io::Triangle {
                normal: stl_io::Normal::new(n),
                vertices: [a, b, c].map(stl_io::Vertex::new),
            }
        })
        .collect();
    write_atomic(path, |mut w| stl_io::write_stl(&mut w, tris.iter()))
}

/// Reads a Wavefront OBJ file; polygons are triangulated, all objects and groups merged.
/// Vertex normals are kept when every vertex has one. Vertices are numbered in order of
/// first use by a face (tobj's single-index layout); unused vertices are dropped.
pub fn read_obj(path: &Path) -> Result<MeshFile, IoError> {
    let file = open(path)?;
    let mut reader = BufReader::new(file);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // Materials do not matter to geometry: never open .mtl files.
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| match e {
        tobj::LoadError::FaceVertexOutOfBounds | tobj::LoadError::FaceNormalOutOfBounds => {
            IoError::BadIndex {
                path: path.into(),
                what: format!("{e} (a face refers to a vertex or normal that does not exist)"),
            }
        }
        tobj::LoadError::ReadError => IoError::Os {
            path: path.into(),
            source: std::io::Error::other("read failed"),
        },
        e => IoError::Invalid {
            path: path.into(),
            what: format!("not a valid OBJ: {e}"),
        },
    })?;
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    for m in &models {
        let base = mesh.positions.len() as u32;
        let p = &m.mesh.positions;
        let nv = p.len() / 3;
        mesh.positions
            .extend(p.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        if m.mesh.normals.len() == p.len() {
            normals.extend(m.mesh.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        } else {
            all_normals = false;
        }
        for t in m.mesh.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= nv) {
                return Err(IoError::BadIndex {
                    path: path.into(),
                    what: format!("face {t:?} refers past the {nv} vertices of '{}'", m.name),
                });
            }
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    if all_normals && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    if mesh.positions.is_empty() {
        return Err(IoError::Invalid {
            path: path.into(),
            what: "no vertices (is this an OBJ file?)".into(),
        });
    }
    mesh_file(
        path,
        mesh,
        Format::Obj,
        vec![format!("{} object(s)", models.len())],
    )
}

/// Writes an OBJ file (`v`, `vn` when there are normals, 1-based `f`).
pub fn write_obj(path: &Path, mesh: &Mesh) -> Result<(), IoError> {
    check_indices(path, mesh)?;
    write_atomic(path, |w| {
        writeln!(w, "# written by glint")?;
        for p in &mesh.positions {
            writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
        }
        if let Some(ns) = &mesh.normals {
            for n in ns {
                writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
            }
        }
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| i + 1);
            if mesh.normals.is_some() {
                writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
            } else {
                writeln!(w, "f {a} {b} {c}")?;
            }
        }
        Ok(())
    })
}

/// Names PLY files use for a per-vertex scalar.
const PLY_SCALAR_NAMES: [&str; 5] = ["scalar", "value", "quality", "intensity", "confidence"];

/// Reads a PLY file, ASCII or binary: `vertex` elements with x, y, z (and nx, ny, nz, and
/// a scalar named one of `scalar`, `value`, `quality`, `intensity`, `confidence`, when
/// present), `face` elements with a `vertex_indices` (or `vertex_index`) list; polygons
/// are split into triangle fans.
pub fn read_ply(path: &Path) -> Result<MeshFile, IoError> {
    let file = open(path)?;
    let mut reader = BufReader::new(file);
    let parser = ply_rs_bw::parser::Parser::<DefaultElement>::new();
    let ply = parser.read_ply(&mut reader).map_err(|e| {
        // ply-rs-bw's messages span lines (the offending text, the parser state): keep
        // the first, so the user gets one line.
        let msg = e
            .to_string()
            .lines()
            .next()
            .unwrap_or_default()
            .trim()
            .to_string();
        if msg.to_ascii_lowercase().contains("magic")
            || msg.contains("ply") && msg.contains("line 1")
        {
            IoError::BadMagic {
                path: path.into(),
                format: "PLY",
                what: msg,
            }
        } else if matches!(e.kind(), std::io::ErrorKind::UnexpectedEof) {
            IoError::Truncated {
                path: path.into(),
                what: msg,
            }
        } else {
            IoError::Invalid {
                path: path.into(),
                what: format!("not a valid PLY: {msg}"),
            }
        }
    })?;
    let invalid = |what: String| IoError::Invalid {
        path: path.into(),
        what,
    };
    let vertices = ply
        .payload
        .get("vertex")
        .ok_or_else(|| invalid("no 'vertex' element".into()))?;
    let get = |v: &DefaultElement, k: &str| v.get(k).and_then(Property::to_f32_lossy);
    let mut mesh = Mesh::default();
    for (i, v) in vertices.iter().enumerate() {
        match (get(v, "x"), get(v, "y"), get(v, "z")) {
            (Some(x), Some(y), Some(z)) => mesh.positions.push([x, y, z]),
            _ => return Err(invalid(format!("vertex {i} lacks numeric x, y, z"))),
        }
    }
    if vertices.first().is_some_and(|v| v.contains_key("nx")) {
        mesh.normals = Some(
            vertices
                .iter()
                .map(|v| [get(v, "nx"), get(v, "ny"), get(v, "nz")])
                .map(|n| match n {
                    [Some(x), Some(y), Some(z)] => Ok([x, y, z]),
                    _ => Err(invalid("a vertex lacks numeric nx, ny, nz".into())),
                })
                .collect::<Result<_, _>>()?,
        );
    }
    if let Some(name) = vertices
        .first()
        .and_then(|v| PLY_SCALAR_NAMES.into_iter().find(|k| v.contains_key(*k)))
    {
        mesh.scalars = Some(
            vertices
                .iter()
                .map(|v| get(v, name).ok_or_else(|| invalid(format!("a vertex lacks '{name}'"))))
                .collect::<Result<_, _>>()?,
        );
    }
    let n = mesh.positions.len();
    if let Some(faces) = ply.payload.get("face") {
        for (k, f) in faces.iter().enumerate() {
            let list = f
                .get("vertex_indices")
                .or_else(|| f.get("vertex_index"))
                .ok_or_else(|| invalid(format!("face {k} has no vertex_indices list")))?;
            let idx = list.to_u32_list().ok_or_else(|| IoError::BadIndex {
                path: path.into(),
                what: format!("face {k} has negative or non-integer indices"),
            })?;
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
                return Err(IoError::BadIndex {
                    path: path.into(),
                    what: format!("face {k} refers to vertex {bad}, past the {n} vertices"),
                });
            }
            for j in 1..idx.len().saturating_sub(1) {
                mesh.triangles.push([idx[0], idx[j], idx[j + 1]]);
            }
        }
    }
    let encoding = match ply.header.encoding {
        Encoding::Ascii => "ASCII PLY",
        Encoding::BinaryLittleEndian => "binary little-endian PLY",
        Encoding::BinaryBigEndian => "binary big-endian PLY",
    };
    mesh_file(path, mesh, Format::Ply, vec![encoding.into()])
}

/// PLY payload encodings for [`write_ply`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyEncoding {
    /// Text.
    Ascii,
    /// Binary, little-endian.
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

/// Writes a PLY file: float x, y, z (nx, ny, nz and `scalar` when present), and uint
/// `vertex_indices` lists of 3.
pub fn write_ply(path: &Path, mesh: &Mesh, encoding: PlyEncoding) -> Result<(), IoError> {
    check_indices(path, mesh)?;
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = match encoding {
        PlyEncoding::Ascii => Encoding::Ascii,
        PlyEncoding::BinaryLittleEndian => Encoding::BinaryLittleEndian,
        PlyEncoding::BinaryBigEndian => Encoding::BinaryBigEndian,
    };
    let float = || PropertyType::Scalar(PlyScalar::Float);
    let mut vdef = ElementDef::new("vertex".into());
    let mut names = vec!["x", "y", "z"];
    if mesh.normals.is_some() {
        names.extend(["nx", "ny", "nz"]);
    }
    if mesh.scalars.is_some() {
        names.push("scalar");
    }
    for name in &names {
        vdef.properties
            .add(PropertyDef::new((*name).into(), float()));
    }
    ply.header.elements.add(vdef);
    let mut fdef = ElementDef::new("face".into());
    fdef.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(PlyScalar::UChar, PlyScalar::UInt),
    ));
    ply.header.elements.add(fdef);
    let verts: Vec<DefaultElement> = (0..mesh.positions.len())
        .map(|i| {
            let mut e = DefaultElement::new();
            let p = mesh.positions[i];
            let mut vals = p.to_vec();
            if let Some(n) = &mesh.normals {
                vals.extend(n[i]);
            }
            if let Some(s) = &mesh.scalars {
                vals.push(s[i]);
            }
            for (name, v) in names.iter().zip(vals) {
                e.insert((*name).into(), Property::Float(v));
            }
            e
        })
        .collect();
    let faces: Vec<DefaultElement> = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut e = DefaultElement::new();
            e.insert("vertex_indices".into(), Property::ListUInt(t.to_vec()));
            e
        })
        .collect();
    ply.payload.insert("vertex".into(), verts);
    ply.payload.insert("face".into(), faces);
    let writer = ply_rs_bw::writer::Writer::<DefaultElement>::new();
    write_atomic(path, |mut w| writer.write_ply(&mut w, &mut ply).map(|_| ()))
}
