//! The thread pool the module's work runs on, rebuilt after a fork.
//!
//! A process that has rendered and then forks (Python's `multiprocessing` default on
//! Linux, Dask's and pytest-xdist's workers) copies rayon's global pool into the child
//! without its threads: the child's first parallel loop would wait forever for workers
//! that do not exist. So the module never uses the global pool: every call runs on a
//! pool of its own ([`detach`]), which a process whose id differs from the pool's
//! builder (a forked child) replaces with a new one.

use std::sync::atomic::{AtomicPtr, Ordering};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// A pool and the process that built it.
struct Pool {
    pid: u32,
    pool: rayon::ThreadPool,
}

/// The current process's pool (null before the first call). Pools are leaked, never
/// freed: a reference handed out stays valid, and a process builds one, plus one in
/// each forked child (dropping a copied pool would signal threads that do not exist).
static POOL: AtomicPtr<Pool> = AtomicPtr::new(std::ptr::null_mut());

/// This process's pool, built on first use and after a fork.
fn pool() -> PyResult<&'static rayon::ThreadPool> {
    let pid = std::process::id();
    let current = POOL.load(Ordering::Acquire);
    // SAFETY: a non-null POOL points to a leaked `Box<Pool>` (below), never freed.
    if let Some(p) = unsafe { current.as_ref() } {
        if p.pid == pid {
            return Ok(&p.pool);
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("glint-{i}"))
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start glint's threads: {e}")))?;
    let fresh: &'static mut Pool = Box::leak(Box::new(Pool { pid, pool }));
    match POOL.compare_exchange(current, fresh, Ordering::AcqRel, Ordering::Acquire) {
        Ok(_) => Ok(&fresh.pool),
        // Another thread installed this process's pool first: use it (ours is leaked
        // unused, once).
        Err(other) => {
            // SAFETY: as above, a non-null POOL is a leaked `Box<Pool>`.
            match unsafe { other.as_ref() } {
                Some(p) if p.pid == pid => Ok(&p.pool),
                _ => Ok(&fresh.pool),
            }
        }
    }
}

/// Runs `f` with the GIL released, on this process's pool (so its parallel loops use
/// threads that exist, also in a forked child).
pub fn detach<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    let pool = pool()?;
    Ok(py.detach(|| pool.install(f)))
}
