//! `glint info FILE --labels`: the labels a label map holds, with their names (from a
//! colour table), voxel counts and volumes in millilitres.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use glint_io::Volume;
use glint_render::label_maps::{LabelGrid, LabelTable};
use glint_render::LabelSpec;
use serde_json::{json, Value};

/// One label present in a map.
struct Row {
    value: u32,
    name: String,
    in_table: bool,
    voxels: u64,
    ml: f64,
    color: [u8; 3],
}

/// The labels of `volume` (read from `path`) named by `table` (a built-in name or a
/// file; default as a scene's label map chooses it).
fn rows(
    path: &Path,
    volume: &Volume,
    table: Option<&str>,
) -> anyhow::Result<(LabelTable, Vec<Row>)> {
    let grid = LabelGrid::from_volume(volume)
        .with_context(|| format!("{}: cannot list labels", path.display()))?;
    let table = match table
        .map(str::to_string)
        .or_else(|| LabelSpec::default_table(path))
    {
        Some(t) => LabelTable::open(&t)?,
        None => LabelTable::new("none"),
    };
    let ml = grid.voxel_ml();
    let rows = grid
        .summary()
        .into_iter()
        .map(|(value, e)| Row {
            value,
            name: table.name_of(value),
            in_table: table.get(value).is_some(),
            voxels: e.voxels,
            ml: e.voxels as f64 * ml,
            color: table.color_of(value),
        })
        .collect();
    Ok((table, rows))
}

/// Appends the label listing to `glint info`'s text.
pub fn print(
    out: &mut String,
    path: &Path,
    volume: &Volume,
    table: Option<&str>,
) -> anyhow::Result<()> {
    let (table, rows) = rows(path, volume, table)?;
    let missing = rows.iter().filter(|r| !r.in_table).count();
    writeln!(
        out,
        "labels:    {} present; table {}: {} entries, {} of them present; {missing} present value(s) not in it",
        rows.len(),
        table.source,
        table.len(),
        rows.len() - missing
    )?;
    writeln!(
        out,
        "  {:>6}  {:<36} {:>10} {:>12}  colour",
        "value", "name", "voxels", "ml"
    )?;
    for r in &rows {
        let mark = if r.in_table { "" } else { " (not in table)" };
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
    table: Option<&str>,
) -> anyhow::Result<()> {
    let (table, rows) = rows(path, volume, table)?;
    v["label_table"] = json!({"source": table.source, "entries": table.len()});
    v["labels"] = rows
        .iter()
        .map(|r| {
            json!({
                "value": r.value,
                "name": r.name,
                "in_table": r.in_table,
                "voxels": r.voxels,
                "ml": r.ml,
                "color": r.color,
            })
        })
        .collect();
    Ok(())
}
