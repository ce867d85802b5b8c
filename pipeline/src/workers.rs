//! The estimator's worker threads: one rayon pool, made with the estimator
//! (never per frame), each worker bound to a CPU of its own when
//! `pin_threads` is on.
//!
//! **Why bind them.** A frame's parallel parts are short (2-8 ms). When the
//! caller hands one to a sleeping worker, Linux wakes the worker on a CPU
//! near the waker, often the caller's own, busy one; the worker then waits
//! there for the scheduler to move it to the idle CPU, and the caller has
//! done most of the work by then. On this project's 2-CPU virtual machine
//! two unbound threads take 0.85-1.11x the latency of one; bound,
//! 0.66-0.83x (BENCHMARKS.md, "Threads"). A bound worker stays on its CPU: other busy
//! processes bound to the same CPUs slow it, which `pin_threads = false`
//! (or a systemd `CPUAffinity=` that gives the service CPUs of its own)
//! avoids. Only the pool's threads are bound, never the caller's.

use std::sync::Arc;

/// The pool of `threads` workers (none for 1). Worker `k` is bound to the
/// `k`-th CPU of the set the process may run on (wrapping) when `pin`;
/// `None` (and a warning) when the system refuses the threads: the stages
/// then run on the caller's thread.
pub(crate) fn worker_pool(threads: usize, pin: bool) -> Option<Arc<rayon::ThreadPool>> {
    if threads <= 1 {
        return None;
    }
    let cpus = if pin {
        core_affinity::get_core_ids().unwrap_or_default()
    } else {
        Vec::new()
    };
    let built = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|k| format!("slope-estimator-{k}"))
        .start_handler(move |k| bind(k, &cpus))
        .build();
    match built {
        Ok(pool) => Some(Arc::new(pool)),
        Err(e) => {
            tracing::warn!(threads, error = %e, "cannot start the estimator's threads: running on one");
            None
        }
    }
}

/// Binds the calling worker `k` to `cpus[k % len]` (nothing for an empty
/// set: not pinning, or the set could not be read).
fn bind(k: usize, cpus: &[core_affinity::CoreId]) {
    if cpus.is_empty() {
        return;
    }
    let cpu = cpus[k % cpus.len()];
    if !core_affinity::set_for_current(cpu) {
        tracing::warn!(
            worker = k,
            cpu = cpu.id,
            "cannot bind an estimator thread to its CPU: it runs unbound"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CPUs the calling thread may run on.
    fn allowed() -> Vec<usize> {
        core_affinity::get_core_ids()
            .unwrap_or_default()
            .into_iter()
            .map(|c| c.id)
            .collect()
    }

    /// Each worker's allowed set, read on the worker itself.
    fn workers_allowed(pool: &rayon::ThreadPool) -> Vec<Vec<usize>> {
        let mut sets = pool.broadcast(|_| allowed());
        sets.sort();
        sets
    }

    #[test]
    fn one_thread_makes_no_pool() {
        assert!(worker_pool(1, true).is_none());
        assert!(worker_pool(0, false).is_none());
    }

    #[test]
    fn pinned_workers_each_run_on_one_cpu_of_the_callers_set() {
        let mine = allowed();
        assert!(!mine.is_empty(), "the test machine's CPU set is readable");
        let pool = worker_pool(2, true).expect("two threads");
        let sets = workers_allowed(&pool);
        assert_eq!(sets.len(), 2);
        for set in &sets {
            assert_eq!(set.len(), 1, "a pinned worker runs on one CPU: {sets:?}");
            assert!(mine.contains(&set[0]), "{set:?} outside {mine:?}");
        }
        if mine.len() >= 2 {
            assert_ne!(sets[0], sets[1], "two workers, two CPUs: {sets:?}");
        }
        // The caller is never bound.
        assert_eq!(allowed(), mine);
    }

    #[test]
    fn unpinned_workers_keep_the_callers_set() {
        let mine = allowed();
        let pool = worker_pool(2, false).expect("two threads");
        assert_eq!(workers_allowed(&pool), vec![mine.clone(), mine]);
    }
}
