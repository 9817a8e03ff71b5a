//! STL (stl_io), OBJ (tobj) and PLY (ply-rs-bw, the maintained fork of ply-rs) surfaces,
//! and the index check every mesh reader ends with.

use std::io::{BufRead, BufReader, Read, Seek};
use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyAccess,
    PropertyAccessResult, PropertyDef, PropertyType, ScalarType as PlyScalar,
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

/// Longest line [`read_obj`] reads: 1 MiB.
pub const OBJ_MAX_LINE: usize = 1 << 20;

/// A reader that fails once a line grows past `limit` bytes, so that a line-by-line
/// parser (tobj reads `lines()`, each a `String`) never holds a longer one. Hand-written:
/// tobj takes any `BufRead` and has no line limit of its own, and no crate bounds
/// `BufRead::lines`.
struct LineBound<R> {
    inner: R,
    limit: usize,
    /// Bytes consumed so far.
    consumed: u64,
    /// Bytes of the current line consumed so far.
    run: usize,
    /// Where the line that was too long starts, once one was.
    over: Option<u64>,
}

impl<R: BufRead> LineBound<R> {
    fn new(inner: R, limit: usize) -> Self {
        LineBound {
            inner,
            limit,
            consumed: 0,
            run: 0,
            over: None,
        }
    }
}

impl<R: BufRead> Read for LineBound<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = {
            let avail = self.fill_buf()?;
            let n = avail.len().min(buf.len());
            buf[..n].copy_from_slice(&avail[..n]);
            n
        };
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineBound<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.run > self.limit {
            self.over = Some(self.consumed - self.run as u64);
            return Err(std::io::Error::other("line too long"));
        }
        self.inner.fill_buf()
    }

    fn consume(&mut self, amt: usize) {
        // The bytes consumed are those fill_buf returned (buffered: no I/O here).
        if let Ok(buf) = self.inner.fill_buf() {
            let done = &buf[..amt.min(buf.len())];
            self.run = match done.iter().rposition(|&b| b == b'\n') {
                Some(i) => done.len() - i - 1,
                None => self.run + done.len(),
            };
        }
        self.consumed += amt as u64;
        self.inner.consume(amt);
    }
}

/// Reads a Wavefront OBJ file; polygons are triangulated, all objects and groups merged.
/// Vertex normals are kept when every vertex has one. Vertices are numbered in order of
/// first use by a face (tobj's single-index layout); unused vertices are dropped.
///
/// A line longer than [`OBJ_MAX_LINE`] is refused as it is read: one polygon line of
/// millions of vertices would otherwise be held, parsed and triangulated whole (a
/// 25 MiB line peaked at 26-35 times the file).
pub fn read_obj(path: &Path) -> Result<MeshFile, IoError> {
    let file = open(path)?;
    let mut reader = LineBound::new(BufReader::new(file), OBJ_MAX_LINE);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    // Materials do not matter to geometry: never open .mtl files.
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    });
    if let Some(at) = reader.over {
        return Err(IoError::Invalid {
            path: path.into(),
            what: format!(
                "the line at byte {at} is longer than {} MiB: not an OBJ line (a vertex \
                 takes tens of bytes, a polygon of 100,000 vertices under 1 MiB)",
                OBJ_MAX_LINE >> 20
            ),
        });
    }
    let (models, _) = loaded.map_err(|e| match e {
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

/// Names PLY files use for a per-vertex scalar, in order of preference.
const PLY_SCALAR_NAMES: [&str; 5] = ["scalar", "value", "quality", "intensity", "confidence"];

/// Largest PLY header read (comments included) before `end_header`.
const PLY_MAX_HEADER: u64 = 1 << 20;

/// Fewest bytes an ASCII PLY value takes: one digit and one separator.
const PLY_ASCII_MIN_VALUE: u64 = 2;

/// One PLY element read through ply-rs-bw's typed [`PropertyAccess`] interface: only
/// what a [`Mesh`] keeps, so no per-element map of names is built (the generic
/// `DefaultElement` took ~35x the file size in memory, issue 17).
#[derive(Default)]
struct PlyItem {
    /// x, y, z, nx, ny, nz.
    coords: [Option<f32>; 6],
    /// The scalar, with its rank in [`PLY_SCALAR_NAMES`] (lower wins).
    scalar: Option<(usize, f32)>,
    /// `vertex_indices` (or `vertex_index`); `Err(())` when an index is negative.
    indices: Option<Result<Vec<u32>, ()>>,
}

impl PropertyAccess for PlyItem {
    fn new() -> Self {
        PlyItem::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(k) = ["x", "y", "z", "nx", "ny", "nz"]
            .iter()
            .position(|&n| n == name)
        {
            self.coords[k] = property.to_f32_lossy();
        } else if let Some(k) = PLY_SCALAR_NAMES.iter().position(|&n| n == name) {
            if let Some(v) = property.to_f32_lossy() {
                if self.scalar.is_none_or(|(r, _)| k < r) {
                    self.scalar = Some((k, v));
                }
            }
        } else if name == "vertex_indices" || name == "vertex_index" {
            self.indices = Some(property.to_u32_list().ok_or(()));
        } else {
            return PropertyAccessResult::Ignored;
        }
        PropertyAccessResult::Set
    }
}

/// Bytes of a binary PLY scalar.
fn ply_scalar_size(t: &PlyScalar) -> u64 {
    match t {
        PlyScalar::Char | PlyScalar::UChar => 1,
        PlyScalar::Short | PlyScalar::UShort => 2,
        PlyScalar::Int | PlyScalar::UInt | PlyScalar::Float => 4,
        PlyScalar::Double => 8,
    }
}

/// The fewest payload bytes one element of `def` can take (lists may be empty).
fn ply_min_element_size(def: &ElementDef, encoding: Encoding) -> u64 {
    def.properties
        .values()
        .map(|p| match (encoding, &p.data_type) {
            (Encoding::Ascii, _) => PLY_ASCII_MIN_VALUE,
            (_, PropertyType::Scalar(t)) => ply_scalar_size(t),
            (_, PropertyType::List(count, _)) => ply_scalar_size(count),
        })
        .sum()
}

/// One line from a ply-rs-bw error (its messages span lines: the offending text, the
/// parser state), mapped to the error kind the user should see.
fn ply_error(path: &Path, e: ply_rs_bw::parser::ParseError) -> IoError {
    let msg = e
        .to_string()
        .lines()
        .next()
        .unwrap_or_default()
        .trim()
        .to_string();
    if msg.to_ascii_lowercase().contains("magic") || msg.contains("ply") && msg.contains("line 1") {
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
}

/// Reads the header text up to `end_header` (at most [`PLY_MAX_HEADER`] bytes) and
/// refuses an element declared twice: ply-rs-bw keeps elements in a map by name, where
/// the second declaration would silently replace the first and misalign the payload.
/// Returns the header's length in bytes.
fn ply_header_scan(path: &Path) -> Result<u64, IoError> {
    let mut head = Vec::new();
    open(path)?
        .take(PLY_MAX_HEADER)
        .read_to_end(&mut head)
        .map_err(|e| os_or_invalid(path, e))?;
    let mut names = std::collections::HashSet::new();
    let mut at = 0usize;
    for line in head.split(|&b| b == b'\n') {
        at += line.len() + 1;
        let text = String::from_utf8_lossy(line);
        let mut words = text.split_whitespace();
        match words.next() {
            Some("end_header") => return Ok(at.min(head.len()) as u64),
            Some("element") => {
                let name = words.next().unwrap_or_default().to_string();
                if !names.insert(name.clone()) {
                    return Err(IoError::Invalid {
                        path: path.into(),
                        what: format!("element '{}' is declared twice", name.escape_debug()),
                    });
                }
            }
            _ => {}
        }
    }
    Err(IoError::Invalid {
        path: path.into(),
        what: format!("no end_header in the first {PLY_MAX_HEADER} bytes"),
    })
}

/// Reads a PLY file, ASCII or binary: `vertex` elements with x, y, z (and nx, ny, nz, and
/// a scalar named one of `scalar`, `value`, `quality`, `intensity`, `confidence`, when
/// present), `face` elements with a `vertex_indices` (or `vertex_index`) list; polygons
/// are split into triangle fans.
///
/// Memory: elements are read one at a time into the mesh (a few times the file size at
/// most), and the element counts of the header are checked against the bytes the file
/// holds before anything is allocated for them.
pub fn read_ply(path: &Path) -> Result<MeshFile, IoError> {
    let header_len = ply_header_scan(path)?;
    let file = open(path)?;
    let file_len = file.metadata().map_err(|e| os_or_invalid(path, e))?.len();
    let mut reader = Reader::new(BufReader::new(file));
    let parser = Parser::<PlyItem>::new();
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| ply_error(path, e))?;
    let mut remaining = file_len.saturating_sub(header_len);
    if header.encoding == Encoding::Ascii {
        // The last value needs no separator when the file lacks a final newline.
        remaining += 1;
    }
    let mut need = 0u64;
    for def in header.elements.values() {
        let min = ply_min_element_size(def, header.encoding);
        need = need.saturating_add(min.saturating_mul(def.count as u64));
        if need > remaining {
            return Err(IoError::SizeMismatch {
                path: path.into(),
                what: format!(
                    "the header announces {} '{}' elements, which with the elements before \
                     them need at least {need} bytes; the file has {remaining} after the header",
                    def.count,
                    def.name.escape_debug()
                ),
            });
        }
    }
    if !header.elements.contains_key("vertex") {
        return Err(IoError::Invalid {
            path: path.into(),
            what: "no 'vertex' element".into(),
        });
    }
    let mut mesh = Mesh::default();
    for def in header.elements.values() {
        let keep = def.name == "vertex" || def.name == "face";
        let mut line = String::new();
        for k in 0..def.count {
            let item = match header.encoding {
                Encoding::Ascii => {
                    line.clear();
                    let got = reader
                        .get_mut()
                        .read_line(&mut line)
                        .map_err(|e| os_or_invalid(path, e))?;
                    if got == 0 {
                        return Err(IoError::Truncated {
                            path: path.into(),
                            what: format!(
                                "the file ends at '{}' element {k} of {}",
                                def.name.escape_debug(),
                                def.count
                            ),
                        });
                    }
                    parser.read_ascii_element(&line, def)
                }
                Encoding::BinaryLittleEndian => {
                    parser.read_little_endian_element(reader.get_mut(), def)
                }
                Encoding::BinaryBigEndian => parser.read_big_endian_element(reader.get_mut(), def),
            }
            .map_err(|e| ply_error(path, e))?;
            if keep {
                ply_add(path, &mut mesh, &def.name, k, item, def.count)?;
            }
        }
    }
    let encoding = match header.encoding {
        Encoding::Ascii => "ASCII PLY",
        Encoding::BinaryLittleEndian => "binary little-endian PLY",
        Encoding::BinaryBigEndian => "binary big-endian PLY",
    };
    mesh_file(path, mesh, Format::Ply, vec![encoding.into()])
}

/// Adds element `k` of `vertex` or `face` to the mesh. Normals and scalars are kept
/// when the first vertex has them, and then required of every vertex.
fn ply_add(
    path: &Path,
    mesh: &mut Mesh,
    element: &str,
    k: usize,
    item: PlyItem,
    count: usize,
) -> Result<(), IoError> {
    let invalid = |what: String| IoError::Invalid {
        path: path.into(),
        what,
    };
    if element == "vertex" {
        let [x, y, z, nx, ny, nz] = item.coords;
        let (Some(x), Some(y), Some(z)) = (x, y, z) else {
            return Err(invalid(format!("vertex {k} lacks numeric x, y, z")));
        };
        if k == 0 {
            // The count passed the size check against the file: at least 3 bytes a
            // vertex, so these are at most 4 (12 / 3) times the file size each.
            mesh.positions.reserve_exact(count);
            if nx.is_some() {
                mesh.normals = Some(Vec::with_capacity(count));
            }
            if item.scalar.is_some() {
                mesh.scalars = Some(Vec::with_capacity(count));
            }
        }
        mesh.positions.push([x, y, z]);
        if let Some(normals) = &mut mesh.normals {
            match (nx, ny, nz) {
                (Some(x), Some(y), Some(z)) => normals.push([x, y, z]),
                _ => return Err(invalid(format!("vertex {k} lacks numeric nx, ny, nz"))),
            }
        }
        if let Some(scalars) = &mut mesh.scalars {
            let (_, v) = item
                .scalar
                .ok_or_else(|| invalid(format!("vertex {k} lacks a scalar")))?;
            scalars.push(v);
        }
        return Ok(());
    }
    let idx = match item.indices {
        None => return Err(invalid(format!("face {k} has no vertex_indices list"))),
        Some(Err(())) => {
            return Err(IoError::BadIndex {
                path: path.into(),
                what: format!("face {k} has negative or non-integer indices"),
            })
        }
        Some(Ok(idx)) => idx,
    };
    let n = mesh.positions.len();
    if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
        return Err(IoError::BadIndex {
            path: path.into(),
            what: format!("face {k} refers to vertex {bad}, past the {n} vertices"),
        });
    }
    for j in 1..idx.len().saturating_sub(1) {
        mesh.triangles.push([idx[0], idx[j], idx[j + 1]]);
    }
    Ok(())
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
