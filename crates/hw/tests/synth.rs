//! The synthesis flow run for real (issue 34): yosys and nextpnr-ice40 on the smallest
//! unit (the Schlick unit with a 4-bit n and 8-bit outputs), and every figure
//! `glint_hw::hdl::synth` parsed from their text output checked against the tools' own
//! machine-readable reports: yosys `stat -json` of the same generic synthesis, the
//! cell types of the iCE40 netlist yosys wrote, and nextpnr's `--report` JSON. In strict
//! mode (glint_testkit) a missing tool fails the test, naming it.

use std::collections::BTreeMap;
use std::process::Command;

use glint_hw::hdl::{synth, HdlUnit, Ports, SchlickUnit, ToolError};
use serde_json::Value;

fn unit() -> SchlickUnit {
    SchlickUnit::new(Ports {
        cos_bits: 16,
        n_bits: 4,
        out_bits: 8,
    })
    .unwrap()
}

/// Cell counts by type of the top module (attribute `top`, or the one named `top`) in a
/// yosys JSON netlist.
fn netlist_cells(json: &Value, top: &str) -> BTreeMap<String, u64> {
    let mut counts = BTreeMap::new();
    let modules = json["modules"].as_object().unwrap();
    let module = modules
        .get(top)
        .or_else(|| {
            modules
                .values()
                .find(|m| m["attributes"].get("top").is_some())
        })
        .unwrap_or_else(|| panic!("no top module in {:?}", modules.keys().collect::<Vec<_>>()));
    let cells = module["cells"].as_object().unwrap();
    for c in cells.values() {
        *counts
            .entry(c["type"].as_str().unwrap().to_string())
            .or_insert(0) += 1;
    }
    counts
}

fn sum_prefix(counts: &BTreeMap<String, u64>, prefix: &str) -> u64 {
    counts
        .iter()
        .filter(|(k, _)| k.starts_with(prefix))
        .map(|(_, v)| v)
        .sum()
}

#[test]
fn synthesis_figures_match_the_tools_own_reports() {
    let u = unit();
    let dir = tempfile::tempdir().unwrap();
    let r = match synth(&u, dir.path()) {
        Err(e @ ToolError::Missing { .. }) => {
            glint_testkit::missing(&e.to_string());
            return;
        }
        r => r.unwrap(),
    };
    glint_testkit::ran("yosys + nextpnr-ice40 synthesis");
    let m = u.module();
    eprintln!("{r:?}");

    // Generic synthesis: the same script as synth.rs, its statistics as yosys's JSON.
    let script = format!(
        "read_verilog {m}.v; synth -flatten -top {m} -run :fine; opt -fast -full; techmap; \
         opt -fast; abc -fast; opt -fast; tee -q -o stat.json stat -json -tech cmos"
    );
    let out = Command::new("yosys")
        .current_dir(dir.path())
        .args(["-q", "-p", &script])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stat: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("stat.json")).unwrap())
            .unwrap();
    let design = &stat["design"];
    assert_eq!(r.cells, design["num_cells"].as_u64().unwrap(), "{design}");
    // yosys 0.23 writes the estimate as a string ("N+" when some cells have no
    // estimate), later versions as a number.
    let transistors = &design["estimated_num_transistors"];
    let transistors = transistors
        .as_u64()
        .or_else(|| transistors.as_str()?.trim_end_matches('+').parse().ok())
        .unwrap_or_else(|| panic!("{design}"));
    assert_eq!(r.transistors, transistors);
    assert!(r.cells > 10 && r.transistors > r.cells, "{r:?}");

    // iCE40: the netlist synth_ice40 wrote, counted by cell type.
    let net: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join(format!("{m}_ice40.json"))).unwrap(),
    )
    .unwrap();
    let cells = netlist_cells(&net, m);
    assert_eq!(r.luts, sum_prefix(&cells, "SB_LUT4"), "{cells:?}");
    assert_eq!(r.carries, sum_prefix(&cells, "SB_CARRY"), "{cells:?}");
    assert_eq!(r.ffs, sum_prefix(&cells, "SB_DFF"), "{cells:?}");
    assert_eq!(r.brams, sum_prefix(&cells, "SB_RAM40_4K"), "{cells:?}");
    assert_eq!(r.dsps, 0, "the HX8K has no DSP blocks");
    assert!(r.luts > 0 && r.ffs > 0, "{cells:?}");

    // Place and route: nextpnr's report. Fmax is the slowest clock's achieved figure, and
    // the placed logic cells hold at least every LUT and flip-flop.
    let pnr: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join(format!("{m}_pnr.json"))).unwrap(),
    )
    .unwrap();
    let fmax = pnr["fmax"]
        .as_object()
        .unwrap()
        .values()
        .map(|c| c["achieved"].as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert_eq!(r.fmax_mhz, fmax, "{}", pnr["fmax"]);
    assert!(fmax > 1.0 && fmax < 1000.0, "{fmax} MHz");
    let lcs = pnr["utilization"]["ICESTORM_LC"]["used"].as_u64().unwrap();
    assert!(lcs >= r.luts.max(r.ffs), "{lcs} logic cells for {r:?}");
    let rams = pnr["utilization"]["ICESTORM_RAM"]["used"].as_u64().unwrap();
    assert_eq!(rams, r.brams);
}
