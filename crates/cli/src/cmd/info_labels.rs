//! `glint info FILE --labels`: the labels a label map holds, with their names (from a
//! colour table), voxel counts and volumes in millilitres.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use glint_io::{Format, ReadOptions, Volume};
use glint_render::label_maps::{LabelGrid, LabelTable};
use serde_json::{json, Value};

/// One label of a map (or, listing all, of its table).
struct Row {
    value: u32,
    name: String,
    in_table: bool,
    /// Whether the map holds the label (listing all, the table's other entries are
    /// listed with 0 voxels).
    present: bool,
    voxels: u64,
    ml: f64,
    color: [u8; 3],
    /// Why an RT structure set's ROI has no voxel.
    note: Option<&'static str>,
}

/// Which labels `glint info --labels` lists.
pub struct Listing<'a> {
    /// The colour table (a built-in name or a file; default as a scene's label map
    /// chooses it).
    pub table: Option<&'a str>,
    /// Every entry of the table too, those the map does not hold with 0 voxels
    /// (default: the labels present only).
    pub all: bool,
}

/// The labels of `volume` (read from `path`) named by the listing's table, in value
/// order.
fn rows(path: &Path, volume: &Volume, listing: &Listing) -> anyhow::Result<(LabelTable, Vec<Row>)> {
    if let Some(rows) = structure_set_rows(path, listing)? {
        return Ok(rows);
    }
    let grid = LabelGrid::from_volume(volume)
        .with_context(|| format!("{}: cannot list labels", path.display()))?;
    let table = LabelTable::for_map(path, listing.table)?;
    let ml = grid.voxel_ml();
    let summary = grid.summary();
    let row = |value: u32, voxels: u64, present: bool| Row {
        value,
        name: table.name_of(value),
        in_table: table.get(value).is_some(),
        present,
        voxels,
        ml: voxels as f64 * ml,
        color: table.color_of(value),
        note: None,
    };
    let mut rows: Vec<Row> = summary
        .iter()
        .map(|(&value, e)| row(value, e.voxels, true))
        .collect();
    if listing.all {
        // The table's background entry (0, "Unknown" in FreeSurfer's) is not a label.
        rows.extend(
            table
                .entries()
                .map(|(v, _)| v)
                .filter(|v| *v != 0 && !summary.contains_key(v))
                .map(|v| row(v, 0, false)),
        );
        rows.sort_by_key(|r| r.value);
    }
    Ok((table, rows))
}

/// The ROIs of an RT structure set, every one listed (an ROI without contours with 0
/// voxels and a note), each with all the voxels inside its contours (where ROIs
/// overlap, the label map gives the voxel to one of them); `None` for any other file.
fn structure_set_rows(
    path: &Path,
    listing: &Listing,
) -> anyhow::Result<Option<(LabelTable, Vec<Row>)>> {
    if !path.is_file() || Format::guess(path).is_some_and(|f| f != Format::Dicom) {
        return Ok(None);
    }
    let Ok(Some(set)) = glint_io::dicom::read_structure_set(path, &ReadOptions::default()) else {
        return Ok(None);
    };
    let table = LabelTable::for_map(path, listing.table)?;
    let ml = set.voxel_ml();
    let rows = set
        .rois
        .iter()
        .zip(&set.voxels)
        .map(|(r, &voxels)| Row {
            value: r.number,
            name: table.name_of(r.number),
            in_table: table.get(r.number).is_some(),
            present: voxels > 0,
            voxels,
            ml: voxels as f64 * ml,
            color: table.color_of(r.number),
            note: match (r.contours, voxels) {
                (0, _) => Some("no closed contour"),
                (_, 0) => Some("encloses no voxel centre"),
                _ => None,
            },
        })
        .collect();
    Ok(Some((table, rows)))
}

/// Appends the label listing to `glint info`'s text.
pub fn print(
    out: &mut String,
    path: &Path,
    volume: &Volume,
    listing: &Listing,
) -> anyhow::Result<()> {
    let (table, rows) = rows(path, volume, listing)?;
    let present = rows.iter().filter(|r| r.present).count();
    let missing = rows.iter().filter(|r| r.present && !r.in_table).count();
    writeln!(
        out,
        "labels:    {present} present; table {}: {} entries, {} of them present; {missing} present value(s) not in it",
        table.source,
        table.len(),
        present - missing
    )?;
    if listing.all {
        writeln!(
            out,
            "           listing every entry of the table: {} not in the map (0 voxels, marked absent)",
            rows.len() - present
        )?;
    }
    writeln!(
        out,
        "  {:>6}  {:<36} {:>10} {:>12}  colour",
        "value", "name", "voxels", "ml"
    )?;
    for r in &rows {
        let note = r.note.map(|n| format!(" ({n})"));
        let mark = match (r.present, r.in_table) {
            _ if note.is_some() => note.as_deref().unwrap_or_default(),
            (false, _) => " (absent)",
            (true, false) => " (not in table)",
            (true, true) => "",
        };
        let [cr, cg, cb] = r.color;
        writeln!(
            out,
            "  {:>6}  {:<36} {:>10} {:>12.3}  #{cr:02x}{cg:02x}{cb:02x}{mark}",
            r.value, r.name, r.voxels, r.ml
        )?;
    }
    Ok(())
}

/// Adds `labels` and `label_table` to `glint info --json`'s object.
pub fn add_json(
    v: &mut Value,
    path: &Path,
    volume: &Volume,
    listing: &Listing,
) -> anyhow::Result<()> {
    let (table, rows) = rows(path, volume, listing)?;
    v["label_table"] = json!({"source": table.source, "entries": table.len()});
    v["labels"] = rows
        .iter()
        .map(|r| {
            let mut row = json!({
                "value": r.value,
                "name": r.name,
                "in_table": r.in_table,
                "present": r.present,
                "voxels": r.voxels,
                "ml": r.ml,
                "color": r.color,
            });
            if let Some(n) = r.note {
                row["note"] = json!(n);
            }
            row
        })
        .collect();
    Ok(())
}
