//! Coarse first (issue 31): a viewer of an OME-Zarr pyramid asked for its `auto` level
//! opens the pyramid's coarsest level (a first frame in a fraction of the time), then
//! reads the `auto` level in the background ([`crate::Viewer::refine`]); each client
//! swaps it in when its camera rests.

use std::path::Path;

use glint_io::zarr::{self, Level};
use glint_io::ReadOptions;
use glint_render::{Input, RenderError, Renderer};
use serde::Serialize;

/// The pyramid level a client's frames are rendered from, as the page shows it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PyramidLevel {
    /// The level (0 finest).
    pub level: usize,
    /// Levels in the pyramid.
    pub levels: usize,
    /// Its voxels along x, y, z.
    pub dims: [usize; 3],
    /// Whether a finer level is being read to replace it.
    pub coarse: bool,
}

/// A level read and ready to render: what [`crate::Viewer::refine`] hands the clients.
pub(crate) struct Stage {
    pub(crate) renderer: Renderer,
    pub(crate) level: PyramidLevel,
    pub(crate) range: [f32; 2],
}

/// How a viewer opens its input: the level it starts from and, when that is a coarse
/// stand-in, the level to read next.
pub(crate) struct Plan {
    /// Read options of the first level.
    pub(crate) first: ReadOptions,
    /// The first level (`None`: not a pyramid).
    pub(crate) level: Option<PyramidLevel>,
    /// The level to read after it, and its options.
    pub(crate) finer: Option<(ReadOptions, PyramidLevel)>,
}

/// The plan for `input` read with `options`: coarse first when it is an OME-Zarr
/// store asked for at [`Level::Auto`] and its coarsest level is not the one asked for.
pub(crate) fn plan(input: &Input, options: &ReadOptions) -> Result<Plan, RenderError> {
    let alone = Plan {
        first: options.clone(),
        level: None,
        finer: None,
    };
    let Input::Path(path) = input else {
        return Ok(alone);
    };
    if !zarr::is_store(Path::new(path)) {
        return Ok(alone);
    }
    let all = zarr::levels(path)?;
    let describe = |level: usize, coarse: bool| PyramidLevel {
        level,
        levels: all.len(),
        dims: all[level].dims,
        coarse,
    };
    // An unknown level index is left for the reader to refuse, in its words.
    let Some(chosen) = zarr::pick(&all, options.level) else {
        return Ok(alone);
    };
    let coarsest = all.len() - 1;
    if !matches!(options.level, Level::Auto(_)) || chosen == coarsest {
        return Ok(Plan {
            level: Some(describe(chosen, false)),
            ..alone
        });
    }
    let first = ReadOptions {
        level: Level::Index(coarsest),
        ..options.clone()
    };
    let finer = ReadOptions {
        level: Level::Index(chosen),
        ..options.clone()
    };
    Ok(Plan {
        first,
        level: Some(describe(coarsest, true)),
        finer: Some((finer, describe(chosen, false))),
    })
}
