//! OME-Zarr (OME-NGFF 0.4 on Zarr v2, 0.5 on Zarr v3) multiscale images: the pyramid's
//! levels from the group's `multiscales` metadata, and one level read as a volume
//! ([`read`]) or opened as a [`Stream`] that hands out boxes of voxels through a
//! bounded cache of decoded chunks (what `glint render` and `glint view` use: the
//! field's bricks are built from the chunks as rays reach them, and the level is never
//! held whole). Both open the level with the same checks (sizes
//! against `max_voxels`, the chunk shape before any chunk is decoded, data type, axes,
//! affine).
//!
//! The arrays are read with `zarrs` (codecs blosc, gzip, zstd, sharding) and the
//! metadata parsed and validated by `ome_zarr_metadata`; this module only maps the
//! image's axes onto glint's grid. The last three spatial axes (x fastest in memory,
//! then y, then z, NGFF's order "t, c, z, y, x") become i, j, k; a time or channel
//! axis is read at index 0 with a note. The affine is the level's scale and
//! translation (NGFF 0.4 "coordinateTransformations"), in the axes' units (mm when
//! they say millimeter, else as given, with a note).

use std::path::Path;
use std::sync::Arc;

use ome_zarr_metadata::v0_4::{self, AxisType, CoordinateTransform};
use ome_zarr_metadata::AnyOmeFields;
use zarrs::array::{Array, ArrayError, ArraySubset, ElementOwned};
use zarrs::filesystem::FilesystemStore;
use zarrs::group::Group;
use zarrs::storage::{ReadableStorageTraits, StorageError};

mod stream;

pub use stream::{Stream, STREAM_MAX_VOXELS};

use crate::common::{check_affine, diagonal_affine};
use crate::{Format, IoError, ReadOptions, Samples, Volume, VolumeFile};

/// Which level of a pyramid to read ([`ReadOptions::level`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Level {
    /// The finest (level 0).
    #[default]
    Finest,
    /// Level `n` (0 finest).
    Index(usize),
    /// The coarsest (what `glint info` reads: the pyramid's metadata without its
    /// largest level's samples).
    Coarsest,
    /// The coarsest level whose largest edge, in voxels, is at least this many (the
    /// image's larger side in pixels: at least one voxel per pixel along the view).
    Auto(usize),
}

/// One level of a pyramid.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelInfo {
    /// The array's path inside the group.
    pub path: String,
    /// Voxels along x, y, z (i, j, k).
    pub dims: [usize; 3],
    /// Voxel size along x, y, z in the axes' units.
    pub scale: [f64; 3],
    /// Offset of voxel (0, 0, 0) along x, y, z.
    pub translation: [f64; 3],
    /// The data type's name (`uint16`, ...).
    pub data_type: String,
}

/// Whether `path` is a Zarr group (a directory with `.zgroup`/`.zattrs` or
/// `zarr.json`).
pub fn is_store(path: &Path) -> bool {
    path.is_dir()
        && ["zarr.json", ".zattrs", ".zgroup"]
            .iter()
            .any(|f| path.join(f).is_file())
}

fn invalid(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Invalid {
        path: path.into(),
        what: what.into(),
    }
}

/// What glint uses of a multiscale image (NGFF 0.4 and 0.5 share these fields).
struct Image {
    axes: Vec<v0_4::Axis>,
    datasets: Vec<v0_4::MultiscaleImageDataset>,
}

/// The store and its first multiscale image.
fn multiscale(path: &Path) -> Result<(Arc<FilesystemStore>, Image), IoError> {
    let store = Arc::new(
        FilesystemStore::new(path).map_err(|e| invalid(path, format!("not a Zarr store: {e}")))?,
    );
    let group = Group::open(store.clone(), "/")
        .map_err(|e| invalid(path, format!("not a Zarr group: {e}")))?;
    let attrs = serde_json::Value::Object(group.attributes().clone());
    let ome: AnyOmeFields = serde_json::from_value(attrs)
        .map_err(|e| invalid(path, format!("no OME-Zarr metadata: {e}")))?;
    let first = match ome {
        AnyOmeFields::V0_4(a) => a.multiscales.and_then(|m| {
            m.into_iter().next().map(|m| Image {
                axes: m.axes,
                datasets: m.datasets,
            })
        }),
        AnyOmeFields::V0_5(o) => o.multiscales.and_then(|m| {
            m.into_iter().next().map(|m| Image {
                axes: m.axes,
                datasets: m.datasets,
            })
        }),
    };
    let image =
        first.ok_or_else(|| invalid(path, "the OME-Zarr group holds no multiscale image"))?;
    Ok((store, image))
}

/// The spatial axes' positions (x, y, z order: the last three spatial axes reversed).
fn spatial_axes(path: &Path, axes: &[v0_4::Axis]) -> Result<[usize; 3], IoError> {
    let spatial: Vec<usize> = (0..axes.len())
        .filter(|&a| matches!(axes[a].r#type, Some(AxisType::Space)))
        .collect();
    match spatial[..] {
        [z, y, x] => Ok([x, y, z]),
        _ => Err(IoError::Unsupported {
            path: path.into(),
            what: format!(
                "an image with {} spatial axes (glint renders 3: z, y, x)",
                spatial.len()
            ),
        }),
    }
}

/// Scale and translation of a dataset along every axis (transforms stored in a file
/// of their own are not read: unsupported).
fn transform(
    path: &Path,
    ts: &[CoordinateTransform],
    n: usize,
) -> Result<(Vec<f64>, Vec<f64>), IoError> {
    let (mut scale, mut shift) = (vec![1.0; n], vec![0.0; n]);
    // ome_zarr_metadata keeps f32: widen the shortest decimal that names it (0.001,
    // not 0.0010000000474974513), the value the store's JSON most likely wrote.
    let wide = |v: &[f32]| {
        v.iter()
            .map(|&x| x.to_string().parse().unwrap_or(f64::from(x)))
            .collect::<Vec<f64>>()
    };
    for t in ts {
        match t {
            CoordinateTransform::Scale(v0_4::CoordinateTransformScale::List { scale: v }) => {
                scale = wide(v)
            }
            CoordinateTransform::Translation(v0_4::CoordinateTransformTranslation::List {
                translation: v,
            }) => shift = wide(v),
            CoordinateTransform::Identity => {}
            _ => {
                return Err(IoError::Unsupported {
                    path: path.into(),
                    what: "coordinate transforms stored in a separate file".into(),
                })
            }
        }
    }
    Ok((scale, shift))
}

/// The pyramid's levels, finest first.
pub fn levels(path: &Path) -> Result<Vec<LevelInfo>, IoError> {
    let (store, image) = multiscale(path)?;
    let xyz = spatial_axes(path, &image.axes)?;
    let n = image.axes.len();
    let mut out = Vec::with_capacity(image.datasets.len().min(64));
    let mut previous: Option<[usize; 3]> = None;
    for d in &image.datasets {
        let array = Array::open(store.clone(), &format!("/{}", d.path))
            .map_err(|e| invalid(path, format!("level '{}': {e}", d.path)))?;
        let shape = array.shape();
        if shape.len() != n {
            return Err(invalid(
                path,
                format!(
                    "level '{}' has {} dimensions, the multiscale's axes {n}",
                    d.path,
                    shape.len()
                ),
            ));
        }
        let dims = xyz.map(|a| usize::try_from(shape[a]).unwrap_or(usize::MAX));
        if let Some(p) = previous {
            if (0..3).any(|a| dims[a] > p[a]) {
                return Err(invalid(
                    path,
                    format!(
                        "level '{}' ({}x{}x{}) is finer than the level before it",
                        d.path, dims[0], dims[1], dims[2]
                    ),
                ));
            }
        }
        previous = Some(dims);
        let (scale, shift) = transform(path, &d.coordinate_transformations, n)?;
        if scale.len() != n || shift.len() != n {
            return Err(invalid(
                path,
                format!(
                    "level '{}': a transform's length is not the axes' {n}",
                    d.path
                ),
            ));
        }
        out.push(LevelInfo {
            path: d.path.clone(),
            dims,
            scale: xyz.map(|a| scale[a]),
            translation: xyz.map(|a| shift[a]),
            // zarrs names a Zarr v2 type by both its v3 and v2 names ("uint16 / <u2").
            data_type: (array.data_type().to_string().split(" / ").next())
                .unwrap_or_default()
                .to_string(),
        });
    }
    if out.is_empty() {
        return Err(invalid(path, "the multiscale image has no datasets"));
    }
    Ok(out)
}

/// Which level `level` picks among `levels` (finest first).
pub fn pick(levels: &[LevelInfo], level: Level) -> Option<usize> {
    match level {
        Level::Finest => Some(0),
        Level::Index(i) => (i < levels.len()).then_some(i),
        Level::Coarsest => levels.len().checked_sub(1),
        Level::Auto(pixels) => Some(
            levels
                .iter()
                .rposition(|l| l.dims.iter().max().copied().unwrap_or(0) >= pixels)
                .unwrap_or(0),
        ),
    }
}

/// One level of a store opened, its metadata checked: what [`read`] and [`Stream`] share.
pub(crate) struct Opened {
    pub(crate) all: Vec<LevelInfo>,
    pub(crate) chosen: usize,
    pub(crate) array: Array<dyn ReadableStorageTraits>,
    /// Index 0 along time and channel axes, the whole extent along the spatial ones.
    pub(crate) ranges: Vec<std::ops::Range<u64>>,
    /// The slowest spatial axis (z) among the array's axes.
    pub(crate) zaxis: usize,
    /// Voxels of the level.
    pub(crate) count: usize,
    pub(crate) affine: [[f64; 4]; 4],
    pub(crate) spacing: [f64; 3],
    /// The version and the time point and channel read.
    pub(crate) notes: Vec<String>,
}

impl Opened {
    /// The level opened.
    pub(crate) fn level(&self) -> &LevelInfo {
        &self.all[self.chosen]
    }
}

/// Opens level [`ReadOptions::level`] of the store at `path` and checks its metadata
/// (its voxels against `level_voxels`, the chunk shape against `max_voxels`, data type,
/// axes, affine) before any chunk is read.
pub(crate) fn open_level(
    path: &Path,
    options: &ReadOptions,
    level_voxels: u64,
) -> Result<Opened, IoError> {
    let all = levels(path)?;
    let chosen = pick(&all, options.level).ok_or_else(|| {
        invalid(
            path,
            format!(
                "no such level: the pyramid has {} (levels 0 to {})",
                all.len(),
                all.len() - 1
            ),
        )
    })?;
    let l = &all[chosen];
    let count = crate::common::checked_voxels(path, l.dims, 1, level_voxels)?;
    let (store, image) = multiscale(path)?;
    let store: Arc<dyn ReadableStorageTraits> = store;
    let array = Array::open(store, &format!("/{}", l.path))
        .map_err(|e| invalid(path, format!("level '{}': {e}", l.path)))?;
    let xyz = spatial_axes(path, &image.axes)?;
    let shape = array.shape().to_vec();
    check_chunks(path, &array, &l.path, options.max_voxels)?;
    let mut notes = vec![format!(
        "OME-Zarr {}, {} level(s)",
        if path.join("zarr.json").is_file() {
            "0.5 (Zarr v3)"
        } else {
            "0.4 (Zarr v2)"
        },
        all.len()
    )];
    let ranges: Vec<std::ops::Range<u64>> = (0..shape.len())
        .map(|a| {
            if xyz.contains(&a) {
                0..shape[a]
            } else {
                0..shape[a].min(1)
            }
        })
        .collect();
    if shape
        .iter()
        .enumerate()
        .any(|(a, &s)| !xyz.contains(&a) && s > 1)
    {
        notes.push("read the first time point and channel".into());
    }
    if xyz != [shape.len() - 1, shape.len() - 2, shape.len() - 3] {
        return Err(IoError::Unsupported {
            path: path.into(),
            what: "spatial axes other than the last three in z, y, x order".into(),
        });
    }
    stream::Stored::of(&l.data_type).ok_or_else(|| IoError::Unsupported {
        path: path.into(),
        what: format!("Zarr data type {}", l.data_type),
    })?;
    let affine = diagonal_affine(l.scale, l.translation);
    let spacing = check_affine(path, &affine)?;
    Ok(Opened {
        chosen,
        array,
        ranges,
        zaxis: xyz[2],
        count,
        affine,
        spacing,
        notes,
        all,
    })
}

/// Reads one level of an OME-Zarr store ([`ReadOptions::level`]) as a volume; the
/// notes list every level, the one read marked. ([`Stream`] reads boxes of a level
/// through a bounded chunk cache instead, never the whole level.)
pub fn read(path: &Path, options: &ReadOptions) -> Result<VolumeFile, IoError> {
    let mut o = open_level(path, options, options.max_voxels)?;
    let samples = read_samples(path, &mut o, options)?;
    if samples.len() != o.count {
        return Err(invalid(path, "the level's data does not match its shape"));
    }
    o.notes.extend(level_notes(&o.all, o.chosen));
    Ok(VolumeFile {
        volume: Volume {
            dims: o.level().dims,
            spacing: o.spacing,
            affine: o.affine,
            samples,
            slope: 1.0,
            intercept: 0.0,
            units: None,
            colour: None,
        },
        format: Format::Zarr,
        notes: o.notes,
        inflate: None,
    })
}

/// Refuses a level whose chunks hold more than `max_voxels` voxels: zarrs decodes a
/// whole chunk before taking what the level needs of it, so a chunk shape from the
/// metadata is checked before any chunk is read.
fn check_chunks(
    path: &Path,
    array: &Array<dyn ReadableStorageTraits>,
    level: &str,
    max_voxels: u64,
) -> Result<(), IoError> {
    let chunk = array
        .chunk_shape(&vec![0; array.shape().len()])
        .map_err(|e| invalid(path, format!("level '{level}': {e}")))?
        .iter()
        .try_fold(1u64, |a, c| a.checked_mul(c.get()))
        .unwrap_or(u64::MAX);
    if chunk > max_voxels {
        return Err(IoError::TooLarge {
            path: path.into(),
            what: format!(
                "level '{level}': chunks of {chunk} voxels exceed the limit of {max_voxels} \
                 (raise it with --max-voxels)"
            ),
        });
    }
    Ok(())
}

/// The samples of the level `o` opened in their stored type, with a note naming the
/// chunks missing (or, `strict`, an error).
fn read_samples(path: &Path, o: &mut Opened, options: &ReadOptions) -> Result<Samples, IoError> {
    let mut missing = (0, 0);
    let l = o.level().clone();
    macro_rules! slabs {
        ($v:ident) => {
            Samples::$v(
                read_slabs(&o.array, &o.ranges, o.zaxis, o.count, &mut missing)
                    .map_err(|e| e.into_io(path, &l.path))?,
            )
        };
    }
    let samples = match l.data_type.as_str() {
        "uint8" => slabs!(U8),
        "int8" => slabs!(I8),
        "uint16" => slabs!(U16),
        "int16" => slabs!(I16),
        "uint32" => slabs!(U32),
        "int32" => slabs!(I32),
        "float32" => slabs!(F32),
        "float64" => slabs!(F64),
        other => {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!("Zarr data type {other}"),
            })
        }
    };
    missing_note(path, &l.path, missing, options.strict, &mut o.notes)?;
    Ok(samples)
}

/// The note on `missing` (chunks absent, chunks in all) of level `level`, pushed onto
/// `notes`; under `strict`, an error instead.
pub(crate) fn missing_note(
    path: &Path,
    level: &str,
    (absent, chunks): (usize, usize),
    strict: bool,
    notes: &mut Vec<String>,
) -> Result<(), IoError> {
    if absent > 0 {
        if strict {
            return Err(invalid(
                path,
                format!(
                    "level '{level}': {absent} of {chunks} chunks are missing (--strict refuses them)"
                ),
            ));
        }
        notes.push(format!(
            "level '{level}': {absent} of {chunks} chunks missing, read as the fill value"
        ));
    }
    Ok(())
}

/// Counts the chunks of `array` that `subset` touches into `missing.1`, and those the
/// store does not hold (read as the array's fill value) into `missing.0`.
pub(crate) fn count_missing(
    array: &Array<dyn ReadableStorageTraits>,
    subset: &ArraySubset,
    missing: &mut (usize, usize),
) -> Result<(), SlabError> {
    let store = array.storage();
    if let Some(chunks) = array
        .chunks_in_array_subset(subset)
        .map_err(|e| SlabError::Array(e.into()))?
    {
        for c in &chunks.indices() {
            missing.1 += 1;
            if store
                .size_key(&array.chunk_key(&c))
                .map_err(SlabError::Storage)?
                .is_none()
            {
                missing.0 += 1;
            }
        }
    }
    Ok(())
}

/// One note per level: path, size, type, voxel size, the one read marked.
fn level_notes(all: &[LevelInfo], chosen: usize) -> Vec<String> {
    all.iter()
        .enumerate()
        .map(|(i, lv)| {
            format!(
                "level {i} '{}': {}x{}x{} {}, voxel {}x{}x{}{}",
                lv.path,
                lv.dims[0],
                lv.dims[1],
                lv.dims[2],
                lv.data_type,
                lv.scale[0],
                lv.scale[1],
                lv.scale[2],
                if i == chosen { " (read)" } else { "" }
            )
        })
        .collect()
}

/// Why a level's chunks could not be read.
pub(crate) enum SlabError {
    Array(ArrayError),
    Storage(StorageError),
    Shape,
}

impl SlabError {
    pub(crate) fn into_io(self, path: &Path, level: &str) -> IoError {
        invalid(
            path,
            match self {
                SlabError::Array(e) => format!("level '{level}': {e}"),
                SlabError::Storage(e) => format!("level '{level}': {e}"),
                SlabError::Shape => format!("level '{level}': its data does not match its shape"),
            },
        )
    }
}

/// Reads the level `ranges` selects one slab of chunks at a time (the chunks sharing
/// a range along the slowest spatial axis `zaxis`, contiguous in glint's x-fastest
/// order) into one vector of `count` samples: the level is held once, plus one slab
/// in transit, never a second full copy. `missing` counts the chunks the store does
/// not hold (read as the array's fill value by `zarrs`) and all the chunks looked at.
fn read_slabs<T: ElementOwned>(
    array: &Array<dyn ReadableStorageTraits>,
    ranges: &[std::ops::Range<u64>],
    zaxis: usize,
    count: usize,
    missing: &mut (usize, usize),
) -> Result<Vec<T>, SlabError> {
    let whole = ArraySubset::new_with_ranges(ranges);
    let grid = array
        .chunks_in_array_subset(&whole)
        .map_err(|e| SlabError::Array(e.into()))?
        .ok_or(SlabError::Shape)?;
    let mut out: Vec<T> = Vec::with_capacity(count);
    let (first, rows) = (grid.start()[zaxis], grid.shape()[zaxis]);
    for cz in first..first + rows {
        let mut index = grid.start().to_vec();
        index[zaxis] = cz;
        let bounded = array
            .chunk_subset_bounded(&index)
            .map_err(SlabError::Array)?;
        let mut slab = ranges.to_vec();
        slab[zaxis] = bounded.start()[zaxis]..bounded.start()[zaxis] + bounded.shape()[zaxis];
        let slab = ArraySubset::new_with_ranges(&slab);
        count_missing(array, &slab, missing)?;
        let part: Vec<T> = array
            .retrieve_array_subset(&slab)
            .map_err(SlabError::Array)?;
        if out.len() + part.len() > count {
            return Err(SlabError::Shape);
        }
        out.extend_from_slice(&part);
    }
    Ok(out)
}
