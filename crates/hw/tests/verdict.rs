//! The verdict of docs/hardware.md is computed from docs/pareto/pareto.csv
//! (`glint_hw::pareto::verdict`), and the CSV's measured rows can seed a cache.

use std::path::{Path, PathBuf};

use glint_hw::hdl::PowParams;
use glint_hw::pareto::verdict::{
    between_markers, cheapest, front, low_path, ratio, ratio_n1, verdict_markdown, Point,
    SLICES_PER_EBR, SLICES_PER_MULT18,
};
use glint_hw::pareto::{
    csv_text, import_csv, key, read_csv, Candidate, Fronts, Measured, Row, CSV_HEADER,
};
use glint_hw::{Config, Design};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn the_verdict_in_docs_hardware_md_is_the_committed_csvs() {
    let rows = read_csv(&repo().join("docs/pareto/pareto.csv")).unwrap();
    let text = verdict_markdown(&rows).unwrap();
    let doc = std::fs::read_to_string(repo().join("docs/hardware.md")).unwrap();
    let held = between_markers(&doc).expect("docs/hardware.md holds the verdict markers");
    assert!(
        held == text.trim_matches('\n'),
        "docs/hardware.md's verdict differs from docs/pareto/pareto.csv's; run\n  \
         glint hw verdict --csv docs/pareto/pareto.csv --write docs/hardware.md"
    );
}

/// One CSV line: `id`, family design, error over n 16-1023 (`n1_15` below 16), cost
/// on every target (`None`: not measured).
fn line(id: &str, design: &Design, err16: f64, n1_15: f64, cost: Option<u32>) -> Vec<String> {
    let mut f = vec![String::new(); CSV_HEADER.len()];
    let set = |f: &mut Vec<String>, name: &str, v: String| {
        let i = CSV_HEADER.iter().position(|&h| h == name).unwrap();
        f[i] = v;
    };
    set(&mut f, "id", id.into());
    set(&mut f, "family", design.family().into());
    set(&mut f, "out_bits", "8".into());
    set(&mut f, "err_pow_n1_15", format!("{n1_15}"));
    for c in ["err_pow_n16_63", "err_pow_n64_255", "err_pow_n256_1023"] {
        set(&mut f, c, format!("{err16}"));
    }
    if let Some(c) = cost {
        for col in ["nand2_eq", "ice40_luts", "ecp5_lut_equiv"] {
            set(&mut f, col, c.to_string());
        }
        // Flip-flop bound on ECP5: slices = ffs / 2.
        set(&mut f, "ecp5_ffs", (4 * c).to_string());
        set(&mut f, "ecp5_mult18", "1".into());
        set(&mut f, "ecp5_brams", "0".into());
    }
    set(&mut f, "design", design.to_json());
    f
}

fn points_of(lines: &[Vec<String>]) -> (Vec<Point>, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pareto.csv");
    let mut w = csv::Writer::from_path(&path).unwrap();
    w.write_record(CSV_HEADER).unwrap();
    for l in lines {
        w.write_record(l).unwrap();
    }
    w.flush().unwrap();
    drop(w);
    let rows = read_csv(&path).unwrap();
    let points = rows.iter().map(|r| Point::from_row(r).unwrap()).collect();
    (points, verdict_markdown(&rows).unwrap())
}

#[test]
fn equal_budget_ratios_take_each_familys_cheapest_design_within_the_budget() {
    let kv = Design::Kv(Config::default());
    let pow = Design::Pow {
        out_bits: 8,
        params: PowParams::default(),
    };
    let (points, text) = points_of(&[
        line("kv-a", &kv, 3.0, 40.0, Some(100)),
        line("kv-b", &kv, 2.5, 40.0, Some(120)),
        line("kv-c", &kv, 4.0, 40.0, Some(130)), // dominated by kv-a
        line("kv-u", &kv, 1.0, 40.0, None),      // not measured: left out
        line("pow-p", &pow, 3.9, 3.9, Some(80)),
        line("pow-q", &pow, 1.0, 1.0, Some(200)),
    ]);
    // Budget 4: kv-a (100) over pow-p (80); 3: kv-a over pow-q (200); 2.6: kv-b over pow-q.
    let r =
        |b: f64| ratio(&points, 8, 0, b, false).map(|(r, k, e)| (r, k.id.clone(), e.id.clone()));
    assert_eq!(r(4.0), Some((1.25, "kv-a".into(), "pow-p".into())));
    assert_eq!(r(3.0), Some((0.5, "kv-a".into(), "pow-q".into())));
    assert_eq!(r(2.6), Some((0.6, "kv-b".into(), "pow-q".into())));
    assert!(ratio(&points, 8, 0, 0.5, false).is_none());
    // Over n 1-1023 K_v is 40 LSB off: no K_v within any budget.
    assert!(cheapest(&points, "kv", 8, 0, 8.0, true).is_none());
    assert_eq!(
        cheapest(&points, "pow", 8, 0, 8.0, true).unwrap().id,
        "pow-p"
    );
    // ECP5 slices: max(LUT-eq, FFs) / 2 = 2 × cost.
    assert_eq!(points[0].cost[3], Some(200.0));
    let ids: Vec<&str> = front(&points, "kv", 8, 0, false)
        .iter()
        .map(|p| p.id.as_str())
        .collect();
    assert_eq!(ids, ["kv-b", "kv-a"]);
    assert!(text.contains("not (fully) measured, so left out where a cost is missing: kv-u"));
    assert!(
        text.contains("K_v cheaper at 2.6, 3 LSB (0.50-0.60×"),
        "{text}"
    );
    assert!(
        text.contains("K_v dearer at 4, 5, 6, 8 LSB (+25 %)"),
        "{text}"
    );
    // Over n 1-1023 K_v needs an n < 16 path: the cheapest exact unit within the budget
    // over n 1-15. At 4 LSB: kv-a (100) + pow-p (80) over pow-p (80) = 2.25.
    let r1 = |b: f64| {
        ratio_n1(&points, 8, 0, b).map(|(r, k, l, e)| (r, k.id.clone(), l.id.clone(), e.id.clone()))
    };
    assert_eq!(
        r1(4.0),
        Some((2.25, "kv-a".into(), "pow-p".into(), "pow-p".into()))
    );
    // At 3 LSB pow-p is too far off: kv-a (100) + pow-q (200) over pow-q (200).
    assert_eq!(
        r1(3.0),
        Some((1.5, "kv-a".into(), "pow-q".into(), "pow-q".into()))
    );
    assert_eq!(low_path(&points, 8, 0, 0.5).map(|p| p.id.as_str()), None);
    assert!(
        text.contains("n 1-1023 (K_v + its n < 16 path), gates (NAND2): K_v dearer at 2.6, 3, 4, 5, 6, 8 LSB (+50 to +125 %)"),
        "{text}"
    );
}

#[test]
fn ecp5_hard_blocks_are_priced_at_their_share_of_the_lfe5u_85f() {
    let kv = Design::Kv(Config::default());
    let (points, _) = points_of(&[line("kv-a", &kv, 3.0, 40.0, Some(100))]);
    // Slices: max(100, 400) / 2 = 200; one MULT18 at 41,820 / 156 slices, no BRAM.
    let priced = points[0].cost[4].unwrap();
    assert!(
        (priced - (200.0 + 41_820.0 / 156.0)).abs() < 1e-9,
        "{priced}"
    );
    assert!((SLICES_PER_MULT18 - 268.08).abs() < 0.01);
    assert!((SLICES_PER_EBR - 201.06).abs() < 0.01);
}

#[test]
fn a_bad_cost_cell_is_one_clear_error() {
    let kv = Design::Kv(Config::default());
    let mut l = line("kv-a", &kv, 3.0, 40.0, Some(100));
    l[CSV_HEADER.iter().position(|&h| h == "nand2_eq").unwrap()] = "many".into();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pareto.csv");
    let mut w = csv::Writer::from_path(&path).unwrap();
    w.write_record(CSV_HEADER).unwrap();
    w.write_record(&l).unwrap();
    w.flush().unwrap();
    drop(w);
    let e = verdict_markdown(&read_csv(&path).unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("kv-a") && e.contains("nand2_eq") && e.contains("many"),
        "{e}"
    );
    assert!(!e.contains('\n'));
}

#[test]
fn the_committed_rows_seed_a_cache_that_writes_them_back() {
    let csv = repo().join("docs/pareto/pareto.csv");
    let rows = read_csv(&csv).unwrap();
    let cache = tempfile::tempdir().unwrap();
    let (new, kept, empty) = import_csv(&csv, cache.path()).unwrap();
    let measured = rows
        .iter()
        .filter(|r| !r.fields[CSV_HEADER.iter().position(|&h| h == "nand2_eq").unwrap()].is_empty())
        .count();
    // Two rows can be one design (the Fig. 4 reference is also a sized design): one entry.
    let mut designs: Vec<String> = rows
        .iter()
        .filter(|r| !r.fields[CSV_HEADER.iter().position(|&h| h == "nand2_eq").unwrap()].is_empty())
        .map(|r| r.design.to_json())
        .collect();
    designs.sort();
    designs.dedup();
    assert_eq!(
        (new, kept, empty),
        (
            designs.len(),
            measured - designs.len(),
            rows.len() - measured
        )
    );
    assert_eq!(
        import_csv(&csv, cache.path()).unwrap(),
        (0, measured, rows.len() - measured)
    );
    // Each measured row, read back from the cache and written again, gives the same
    // error, cost and verification cells.
    let col = |n: &str| CSV_HEADER.iter().position(|&h| h == n).unwrap();
    for r in rows
        .iter()
        .filter(|r| !r.fields[col("nand2_eq")].is_empty())
    {
        let vectors: usize = r.fields[col("cosim_vectors")].parse().unwrap();
        let file = cache
            .path()
            .join(key(&r.design, vectors))
            .join("measured.json");
        let m: Measured = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        let row = Row {
            candidate: Candidate {
                id: r.id.clone(),
                target: r.fields[col("target")].clone(),
                design: r.design.clone(),
            },
            measured: m,
            fronts: Fronts::default(),
        };
        let text = csv_text(&[row]).unwrap();
        let mut rd = csv::Reader::from_reader(text.as_bytes());
        let back: Vec<String> = rd
            .records()
            .next()
            .unwrap()
            .unwrap()
            .iter()
            .map(String::from)
            .collect();
        for c in (col("err_lobe")..=col("ecp5_lut_equiv"))
            .chain(col("lint_clean")..=col("cosim_mismatches"))
        {
            assert_eq!(back[c], r.fields[c], "{} {}", r.id, CSV_HEADER[c]);
        }
    }
}
