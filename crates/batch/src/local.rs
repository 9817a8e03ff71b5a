//! A study on this machine (inputs in parallel on threads), and the files that close
//! every run, local or distributed: `results.jsonl` and `index.html`.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use crate::job::write_if_changed;
use crate::report::report_html;
use crate::row::Status;
use crate::{os_error, run_job, BatchError, Item, Outcome, Row, Spec};

/// The results table: one JSON row per line, sorted by id.
pub const RESULTS_FILE: &str = "results.jsonl";
/// The static report.
pub const REPORT_FILE: &str = "index.html";

/// How to run a study on this machine.
#[derive(Clone, Debug, Default)]
pub struct LocalOptions {
    /// Inputs made at once (0: one per core). Each input's views render on all the
    /// pool's threads.
    pub jobs: usize,
    /// Threads rendering (0: one per core).
    pub threads: usize,
    /// Make every input again, even those already made.
    pub force: bool,
}

/// Counts of a finished study.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Inputs whose outputs exist.
    pub ok: usize,
    /// Inputs that failed.
    pub failed: usize,
}

/// Runs [`run_job`] for every item, `options.jobs` at a time in input order, on a
/// pool of `options.threads` threads; `progress` is called after each input, from the
/// thread that made it. Returns the outcomes in the items' order. Fails only when the
/// spec is unusable, the output directory cannot be made or no thread can start:
/// inputs fail in their rows.
pub fn run_local(
    items: &[Item],
    spec: &Spec,
    out: &Path,
    options: &LocalOptions,
    progress: &(dyn Fn(&Outcome) + Sync),
) -> Result<Vec<Outcome>, BatchError> {
    spec.check()?;
    std::fs::create_dir_all(out).map_err(|e| os_error(out, e))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads)
        .thread_name(|i| format!("glint-batch-{i}"))
        .build()
        .map_err(|e| BatchError::Spec(format!("cannot start the render threads: {e}")))?;
    let cores = pool.current_num_threads();
    let lanes = if options.jobs == 0 {
        cores
    } else {
        options.jobs
    };
    let lanes = lanes.clamp(1, items.len().max(1));
    // Lanes outside the pool take the next input each, so no more than `lanes` volumes
    // are in memory (a rayon task per input could start another input while one waits
    // on its render's tiles).
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; items.len()]);
    std::thread::scope(|scope| {
        for _ in 0..lanes {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else {
                    break;
                };
                let outcome = pool.install(|| run_job(item, spec, out, options.force));
                progress(&outcome);
                done.lock().unwrap_or_else(|p| p.into_inner())[i] = Some(outcome);
            });
        }
    });
    let done = done.into_inner().unwrap_or_else(|p| p.into_inner());
    Ok(done
        .into_iter()
        .map(|o| o.expect("every lane ran until no item was left"))
        .collect())
}

/// Writes `results.jsonl` (the rows sorted by id, one per line) and `index.html`
/// into `out`, each atomically and only when its contents change (a rerun that made
/// nothing new rewrites nothing).
pub fn finish(out: &Path, rows: &[Row]) -> Result<Summary, BatchError> {
    let mut rows: Vec<&Row> = rows.iter().collect();
    rows.sort_by(|a, b| a.id.cmp(&b.id));
    let mut table = String::new();
    for row in &rows {
        table.push_str(&row.to_line());
        table.push('\n');
    }
    std::fs::create_dir_all(out).map_err(|e| os_error(out, e))?;
    write_if_changed(&out.join(RESULTS_FILE), table.as_bytes())?;
    write_if_changed(
        &out.join(REPORT_FILE),
        report_html(rows.iter().copied()).as_bytes(),
    )?;
    let failed = rows.iter().filter(|r| r.status == Status::Failed).count();
    Ok(Summary {
        ok: rows.len() - failed,
        failed,
    })
}
