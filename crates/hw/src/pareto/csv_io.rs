//! `pareto.csv`: one row per design (see [`CSV_HEADER`] for the columns).

use std::path::Path;

use super::{key, Measured, ParetoError, Row, Verified, TARGETS};
use crate::hdl::Costs;
use crate::{Config, Design, DesignErrors};

/// The columns, in order. Errors are in output LSBs; `err_pow_*` are against `cos^n`
/// for the `n` range named; `front_<target>` is the front of error against `cos^n`
/// (n 16-1023) and `front_<target>_lobe` that of error against the own lobe, each within
/// the family and output width. `measured_at` (UTC) and `tools` (flow and tool
/// versions) say when and with what the costs were measured; a design whose costs are
/// not measured has empty cost, lint, co-simulation, `measured_at` and `tools` cells.
/// The extra flows' cells (`ice40_fmax_seeds_mhz`: every seed's Fmax, `;`-separated,
/// seed 1 first; their median and LUT·ns at the median; `ecp5_nodsp_*`: `synth_ecp5
/// -nodsp`) are empty where those flows have not run on the design.
/// `design` is the JSON `glint hw check --config` reads.
pub const CSV_HEADER: [&str; 57] = [
    "id",
    "family",
    "out_bits",
    "target",
    "v",
    "coefficients",
    "coef_source",
    "squarer",
    "square_guard",
    "widths",
    "err_lobe",
    "err_pow_n1_15",
    "err_pow_n16_63",
    "err_pow_n64_255",
    "err_pow_n256_1023",
    "err_pow_all",
    "rom_bits",
    "latency",
    "results_per_clock",
    "nand2_eq",
    "transistors",
    "gate_cells",
    "ice40_luts",
    "ice40_carries",
    "ice40_ffs",
    "ice40_brams",
    "ice40_fmax_mhz",
    "ice40_lut_ns_per_result",
    "ecp5_luts",
    "ecp5_ccu2",
    "ecp5_ffs",
    "ecp5_mult18",
    "ecp5_brams",
    "ecp5_lutram",
    "ecp5_lut_equiv",
    "lint_clean",
    "cosim_vectors",
    "cosim_mismatches",
    "front_gates",
    "front_ice40",
    "front_ecp5",
    "front_gates_lobe",
    "front_ice40_lobe",
    "front_ecp5_lobe",
    "seconds",
    "measured_at",
    "tools",
    "ice40_fmax_seeds_mhz",
    "ice40_fmax_median_mhz",
    "ice40_lut_ns_median",
    "ecp5_nodsp_luts",
    "ecp5_nodsp_ccu2",
    "ecp5_nodsp_ffs",
    "ecp5_nodsp_brams",
    "ecp5_nodsp_lutram",
    "ecp5_nodsp_lut_equiv",
    "design",
];

/// Older headers, read (never written): the columns before `measured_at` and `tools`
/// were added, and before the extra flows' columns; each is a prefix of
/// [`CSV_HEADER`] followed by `design`, and its rows read with the rest empty.
const OLDER_COLUMNS: [usize; 2] = [46, 48];

/// The extra flows' cells (empty where they have not run).
fn extra_cells(c: Option<&Costs>) -> Vec<String> {
    let mut cells = vec![String::new(); 9];
    let Some(c) = c else {
        return cells;
    };
    if !c.ice40_fmax_seeds.is_empty() {
        let seeds: Vec<String> = c
            .ice40_fmax_seeds
            .iter()
            .map(|f| format!("{f:.2}"))
            .collect();
        let med = c.ice40_fmax_median();
        cells[0] = seeds.join(";");
        cells[1] = format!("{med:.2}");
        cells[2] = format!("{:.0}", c.ice40_luts as f64 * 1000.0 / med);
    }
    if let Some(e) = &c.ecp5_nodsp {
        cells[3] = e.luts.to_string();
        cells[4] = e.ccu2.to_string();
        cells[5] = e.ffs.to_string();
        cells[6] = e.brams.to_string();
        cells[7] = e.lutram.to_string();
        cells[8] = e.lut_equiv().to_string();
    }
    cells
}

/// A design's widths in one field.
pub fn widths(d: &Design) -> String {
    match d {
        Design::Kv(c) => kv_widths(c),
        Design::Pow { params: p, .. } => format!(
            "log {}{} UQ1.{} / exp {}{} UQ1.{}",
            1u32 << p.log_index,
            if p.log_interp { "i" } else { "" },
            p.log_frac,
            1u32 << p.exp_index,
            if p.exp_interp { "i" } else { "" },
            p.exp_frac
        ),
        Design::Schlick { params: p, .. } => {
            format!("quotient UQ1.{} / x UQ1.{}", p.quot_frac, p.x_frac)
        }
    }
}

fn kv_widths(c: &Config) -> String {
    let sq: Vec<String> = c.square_frac.iter().map(|w| w.to_string()).collect();
    format!(
        "coef {} / mul {} / sq {}",
        c.coef_bits,
        c.mul_frac,
        sq.join(",")
    )
}

fn b(x: bool) -> String {
    u8::from(x).to_string()
}

/// The 16 cost cells, `nand2_eq` to `ecp5_lut_equiv` (empty when not measured).
fn cost_cells(c: Option<&Costs>) -> Vec<String> {
    let Some(c) = c else {
        return vec![String::new(); 16];
    };
    vec![
        format!("{:.1}", c.nand2()),
        c.transistors.to_string(),
        c.gate_cells.to_string(),
        c.ice40_luts.to_string(),
        c.ice40_carries.to_string(),
        c.ice40_ffs.to_string(),
        c.ice40_brams.to_string(),
        format!("{:.2}", c.ice40_fmax),
        format!("{:.0}", c.ice40_lut_ns()),
        c.ecp5_luts.to_string(),
        c.ecp5_ccu2.to_string(),
        c.ecp5_ffs.to_string(),
        c.ecp5_mult18.to_string(),
        c.ecp5_brams.to_string(),
        c.ecp5_lutram.to_string(),
        c.ecp5_lut_equiv().to_string(),
    ]
}

/// The CSV text of `rows`.
pub fn csv_text(rows: &[Row]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(CSV_HEADER)?;
    for r in rows {
        let d = &r.candidate.design;
        let m = &r.measured;
        let e = &m.errors;
        let (v, coef, src, sq, guard) = match d {
            Design::Kv(k) => (
                k.v.to_string(),
                k.coefficients.name().to_string(),
                k.coef_source.name().to_string(),
                k.squarer.name().to_string(),
                if k.squarer == crate::Squarer::Truncated {
                    k.square_guard.to_string()
                } else {
                    String::new()
                },
            ),
            _ => Default::default(),
        };
        let f = |x: f64| format!("{x:.4}");
        let mut rec = vec![
            r.candidate.id.clone(),
            d.family().to_string(),
            d.out_bits().to_string(),
            r.candidate.target.clone(),
            v,
            coef,
            src,
            sq,
            guard,
            widths(d),
            f(e.lobe),
        ];
        rec.extend(e.power.iter().map(|&x| f(x)));
        rec.extend([
            f(e.power_all),
            m.rom_bits.to_string(),
            m.latency.to_string(),
            "1".to_string(),
        ]);
        rec.extend(cost_cells(m.costs.as_ref()));
        rec.extend(match &m.verified {
            Some(v) => [
                b(v.lint_clean),
                v.vectors.to_string(),
                v.mismatches.to_string(),
            ],
            None => Default::default(),
        });
        rec.extend(r.fronts.power.iter().map(|&x| b(x)));
        rec.extend(r.fronts.lobe.iter().map(|&x| b(x)));
        rec.push(format!("{:.0}", m.seconds));
        rec.push(m.measured_at.clone());
        rec.push(m.tools.clone());
        rec.extend(extra_cells(m.costs.as_ref()));
        rec.push(d.to_json());
        debug_assert_eq!(rec.len(), CSV_HEADER.len());
        w.write_record(&rec)?;
    }
    let bytes = w.into_inner().map_err(|e| e.into_error())?;
    Ok(String::from_utf8(bytes).expect("the CSV is built from UTF-8 strings"))
}

/// Writes `rows` to `path` atomically.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<(), ParetoError> {
    let text = csv_text(rows).map_err(|e| ParetoError::file(path, e))?;
    glint_io::write_atomic(path, |w| w.write_all(text.as_bytes()))
        .map_err(|e| ParetoError::file(path, e))
}

/// One row read back: id, design, on any front, and the text of every column.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvRow {
    /// `id`.
    pub id: String,
    /// `design`, parsed.
    pub design: Design,
    /// Any `front_*` column is 1.
    pub on_front: bool,
    /// Every field, by [`CSV_HEADER`] position.
    pub fields: Vec<String>,
}

/// Reads a `pareto.csv` (as [`write_csv`] writes it; the header must match, or be an
/// older one (without `measured_at` and `tools`, or without the extra flows'
/// columns), whose rows read with those cells empty).
pub fn read_csv(path: &Path) -> Result<Vec<CsvRow>, ParetoError> {
    let mut r = csv::Reader::from_path(path).map_err(|e| ParetoError::file(path, e))?;
    let header = r.headers().map_err(|e| ParetoError::file(path, e))?.clone();
    let older = OLDER_COLUMNS.iter().copied().find(|&n| {
        header
            .iter()
            .eq(CSV_HEADER[..n - 1].iter().chain([&"design"]).copied())
    });
    if older.is_none() && header.iter().ne(CSV_HEADER.iter().copied()) {
        return Err(ParetoError::file(
            path,
            "not a glint hw pareto CSV (its header differs)",
        ));
    }
    let front_cols: Vec<usize> = (0..CSV_HEADER.len())
        .filter(|&i| CSV_HEADER[i].starts_with("front_"))
        .collect();
    debug_assert_eq!(front_cols.len(), 2 * TARGETS.len());
    let mut out = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| ParetoError::file(path, e))?;
        let mut fields: Vec<String> = rec.iter().map(str::to_string).collect();
        if let Some(n) = older {
            if fields.len() != n {
                return Err(ParetoError::file(
                    path,
                    format!(
                        "row {}: {} fields, the header has {n}",
                        fields[0],
                        fields.len()
                    ),
                ));
            }
            let at = fields.len() - 1;
            fields.splice(at..at, vec![String::new(); CSV_HEADER.len() - n]);
        }
        let design = Design::from_json(&fields[CSV_HEADER.len() - 1])
            .map_err(|e| ParetoError::file(path, e))?;
        out.push(CsvRow {
            id: fields[0].clone(),
            design,
            on_front: front_cols.iter().any(|&i| fields[i] == "1"),
            fields,
        });
    }
    Ok(out)
}

fn field<'a>(row: &'a CsvRow, name: &str) -> &'a str {
    let i = CSV_HEADER
        .iter()
        .position(|&h| h == name)
        .expect("a column of CSV_HEADER");
    row.fields[i].trim()
}

fn parse<T: std::str::FromStr>(row: &CsvRow, name: &str) -> Result<T, String> {
    let text = field(row, name);
    text.parse()
        .map_err(|_| format!("row {}: column {name}: {text:?} is not a number", row.id))
}

/// The Fmax a row records, as precisely as its columns allow: `ice40_fmax_mhz` keeps 2
/// decimals and `ice40_lut_ns_per_result` (LUTs × 1000 / Fmax) none, so each bounds
/// the Fmax to an interval; the middle of their intersection writes both columns back
/// as they were (the printed Fmax where the intervals do not meet).
fn fmax_of(row: &CsvRow) -> Result<f64, String> {
    let printed: f64 = parse(row, "ice40_fmax_mhz")?;
    let luts: f64 = parse(row, "ice40_luts")?;
    let lut_ns: f64 = parse(row, "ice40_lut_ns_per_result")?;
    let lo = (printed - 0.005).max(luts * 1000.0 / (lut_ns + 0.5));
    let hi = (printed + 0.005).min(luts * 1000.0 / (lut_ns - 0.5));
    let mid = (lo + hi) / 2.0;
    let same = |f: f64| {
        format!("{f:.2}") == format!("{printed:.2}")
            && format!("{:.0}", luts * 1000.0 / f) == format!("{lut_ns:.0}")
    };
    Ok(if lo < hi && same(mid) { mid } else { printed })
}

/// The measurement a CSV row records, or `None` if its costs are empty.
fn measured_of(row: &CsvRow) -> Result<Option<Measured>, String> {
    if field(row, "nand2_eq").is_empty() {
        return Ok(None);
    }
    let p = |n: &str| parse::<f64>(row, n);
    let u = |n: &str| parse::<u64>(row, n);
    let costs = Costs {
        gate_cells: u("gate_cells")?,
        transistors: u("transistors")?,
        ice40_luts: u("ice40_luts")?,
        ice40_carries: u("ice40_carries")?,
        ice40_ffs: u("ice40_ffs")?,
        ice40_brams: u("ice40_brams")?,
        ice40_fmax: fmax_of(row)?,
        ecp5_luts: u("ecp5_luts")?,
        ecp5_ccu2: u("ecp5_ccu2")?,
        ecp5_ffs: u("ecp5_ffs")?,
        ecp5_mult18: u("ecp5_mult18")?,
        ecp5_brams: u("ecp5_brams")?,
        ecp5_lutram: u("ecp5_lutram")?,
        ice40_fmax_seeds: Vec::new(),
        ecp5_nodsp: None,
    };
    let mut costs = costs;
    let seeds = field(row, "ice40_fmax_seeds_mhz");
    if !seeds.is_empty() {
        costs.ice40_fmax_seeds = seeds
            .split(';')
            .map(|t| {
                t.trim().parse::<f64>().map_err(|_| {
                    format!(
                        "row {}: column ice40_fmax_seeds_mhz: {t:?} is not a number",
                        row.id
                    )
                })
            })
            .collect::<Result<_, _>>()?;
        // Seed 1's Fmax at the precision the other columns give it.
        costs.ice40_fmax_seeds[0] = costs.ice40_fmax;
    }
    if !field(row, "ecp5_nodsp_luts").is_empty() {
        costs.ecp5_nodsp = Some(crate::hdl::Ecp5Cells {
            luts: u("ecp5_nodsp_luts")?,
            ccu2: u("ecp5_nodsp_ccu2")?,
            ffs: u("ecp5_nodsp_ffs")?,
            mult18: 0,
            brams: u("ecp5_nodsp_brams")?,
            lutram: u("ecp5_nodsp_lutram")?,
        });
    }
    let or = |name: &str, default: &str| {
        let t = field(row, name);
        if t.is_empty() {
            default.to_string()
        } else {
            t.to_string()
        }
    };
    Ok(Some(Measured {
        errors: DesignErrors {
            lobe: p("err_lobe")?,
            power: [
                p("err_pow_n1_15")?,
                p("err_pow_n16_63")?,
                p("err_pow_n64_255")?,
                p("err_pow_n256_1023")?,
            ],
            power_all: p("err_pow_all")?,
        },
        costs: Some(costs),
        rom_bits: u("rom_bits")?,
        latency: parse(row, "latency")?,
        verified: Some(Verified {
            lint_clean: field(row, "lint_clean") == "1",
            vectors: u("cosim_vectors")?,
            mismatches: u("cosim_mismatches")?,
        }),
        seconds: p("seconds")?,
        measured_at: or("measured_at", "not recorded"),
        tools: or("tools", "not recorded"),
    }))
}

/// Puts every measured row of the `pareto.csv` at `path` into the exploration's
/// `cache` (the entry a run with the row's co-simulation vector count looks up), so a
/// run on another machine resumes from the committed results instead of measuring
/// them again. Entries already in the cache are kept. Returns (rows imported, rows
/// already cached, rows without costs).
///
/// The CSV keeps the errors to 4 decimals and Fmax to 2, so an imported entry is the
/// CSV's figures, not the original run's full precision.
pub fn import_csv(path: &Path, cache: &Path) -> Result<(usize, usize, usize), ParetoError> {
    let rows = read_csv(path)?;
    let (mut new, mut kept, mut empty) = (0, 0, 0);
    for row in &rows {
        let Some(m) = measured_of(row).map_err(|e| ParetoError::file(path, e))? else {
            empty += 1;
            continue;
        };
        let vectors = m.verified.map_or(0, |v| v.vectors) as usize;
        let entry = cache.join(key(&row.design, vectors));
        let file = entry.join("measured.json");
        if file.exists() {
            kept += 1;
            continue;
        }
        std::fs::create_dir_all(&entry).map_err(|e| ParetoError::file(&entry, e))?;
        let text = serde_json::to_string_pretty(&m).map_err(|e| ParetoError::file(&file, e))?;
        glint_io::write_atomic(&file, |w| w.write_all(text.as_bytes()))
            .map_err(|e| ParetoError::file(&file, e))?;
        new += 1;
    }
    Ok((new, kept, empty))
}
