//! The in-order block pipeline: blocks solved on a few threads, each
//! taking the next as it finishes one, and written in order on the
//! calling thread.

/// A task's parameters and results of one block (column-major where the
/// program solves a Parquet or Arrow block, else row-major) and its row
/// errors.
#[derive(Default)]
pub(super) struct Buffers {
    pub(super) params: Vec<f64>,
    /// `params` is column-major.
    pub(super) params_by_columns: bool,
    pub(super) results: Vec<f64>,
    pub(super) messages: Vec<Option<String>>,
    /// The rows of `messages` that are set, in order.
    pub(super) failed_rows: Vec<usize>,
}

impl Buffers {
    /// The messages of a block of `len` rows: each failed row's, in any
    /// order (a later message for a row replaces an earlier one).
    pub(super) fn set_messages(
        &mut self,
        len: usize,
        failed: impl IntoIterator<Item = (usize, String)>,
    ) {
        let Buffers {
            messages,
            failed_rows,
            ..
        } = self;
        // Most blocks have no failed row: a buffer of the same length is
        // cleared only where the last block set it (a block's 16 384
        // messages are 384 KiB to write).
        if messages.len() == len {
            for r in failed_rows.drain(..) {
                messages[r] = None;
            }
        } else {
            messages.clear();
            messages.resize(len, None);
            failed_rows.clear();
        }
        for (r, e) in failed {
            messages[r] = Some(e);
            failed_rows.push(r);
        }
        failed_rows.sort_unstable();
        failed_rows.dedup();
    }
}

/// Blocks `0..all`: `solve` on this thread and on `threads - 1` helper
/// threads (each with its own buffers, taking the next block as it finishes
/// one), and `write` on this thread, in order. A thread takes no block
/// `ahead` times `threads` past the last one written, so memory stays that
/// many blocks whatever the batch. The first error of `write` stops the
/// helpers (their blocks in progress are dropped) and is returned.
///
/// This thread writes the blocks that are ready between its own solves, and
/// waits only when the window is full. So a batch on `threads` cores runs
/// `threads` threads, not one more that wakes for every block: on a 2-core
/// KVM guest, a thread woken while both cores were busy waited up to a
/// 4 ms scheduler tick, and one started on an idle core ran 1 to 4 ms later
/// (docs/performance.md (history: git log -p -- docs/benchmarks.md), "The writer solves too").
pub(super) fn in_order<T: Send>(
    all: usize,
    ahead: usize,
    threads: usize,
    solve: &(impl Fn((&mut Buffers, usize)) -> T + Sync),
    mut write: impl FnMut(T) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::{Condvar, Mutex, mpsc};
    let threads = threads.max(1);
    let mut buffers = Buffers::default();
    if threads == 1 || all <= 1 {
        return (0..all).try_for_each(|i| write(solve((&mut buffers, i))));
    }
    let window = ahead.max(1) * threads;
    let next = AtomicUsize::new(0);
    // Blocks written, with the condition the helpers wait on.
    let written = (Mutex::new(0usize), Condvar::new());
    let stop = AtomicBool::new(false);
    // Stops every helper when dropped on this thread (at the end, or on an
    // error), or when a helper unwinds (this thread would wait forever for
    // its block); `.2` says which. The flag is set under the lock, so that
    // a helper between its test and its wait cannot miss the wake-up.
    struct Stop<'a>(&'a AtomicBool, &'a (Mutex<usize>, Condvar), bool);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            if self.2 || std::thread::panicking() {
                let _lock = self.1.0.lock().unwrap_or_else(|e| e.into_inner());
                self.0.store(true, Ordering::SeqCst);
                self.1.1.notify_all();
            }
        }
    }
    let (tx, rx) = mpsc::channel::<(usize, T)>();
    std::thread::scope(|scope| {
        // No more helpers than blocks for them.
        for _ in 1..threads.min(all) {
            let (tx, next, written, stop) = (tx.clone(), &next, &written, &stop);
            scope.spawn(move || {
                let _stop = Stop(stop, written, false);
                let mut buffers = Buffers::default();
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    if i >= all {
                        break;
                    }
                    let mut done = written.0.lock().unwrap_or_else(|e| e.into_inner());
                    while i >= *done + window && !stop.load(Ordering::SeqCst) {
                        done = written.1.wait(done).unwrap_or_else(|e| e.into_inner());
                    }
                    drop(done);
                    if stop.load(Ordering::SeqCst)
                        || tx.send((i, solve((&mut buffers, i)))).is_err()
                    {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let _stop = Stop(&stop, &written, true);
        // Blocks come in the order they finish; each waits here for those before it.
        let mut pending: std::collections::BTreeMap<usize, T> = Default::default();
        let mut at = 0;
        while at < all {
            // The next block, if it is within the window: this thread's to
            // solve. (A helper that took a block past the window waits.)
            let mine = next
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |i| {
                    (i < all && i < at + window).then_some(i + 1)
                })
                .ok();
            match mine {
                Some(i) => {
                    pending.insert(i, solve((&mut buffers, i)));
                    pending.extend(rx.try_iter());
                }
                None => match rx.recv() {
                    Ok((i, d)) => {
                        pending.insert(i, d);
                    }
                    Err(_) => {
                        anyhow::bail!("a batch task stopped before its block {at} was written")
                    }
                },
            }
            let before = at;
            while let Some(d) = pending.remove(&at) {
                write(d)?;
                at += 1;
            }
            if at > before {
                *written.0.lock().unwrap_or_else(|e| e.into_inner()) = at;
                written.1.notify_all();
            }
        }
        Ok(())
    })
}

/// The block tasks of `egt batch` ([`in_order`]): `--threads`, else
/// rayon's own rule (`RAYON_NUM_THREADS`, else the machine's parallelism).
/// Found without starting rayon's global pool: the tasks run on pools of
/// their own, and the global pool's idle threads would spin beside them
/// (about 3.5 ms of CPU in a 17 ms run of 10^6 rows on 2 cores,
/// docs/performance.md (history: git log -p -- docs/benchmarks.md)).
pub(super) fn batch_threads(requested: Option<usize>) -> usize {
    let asked = requested.or_else(|| {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|n| n.trim().parse::<usize>().ok())
            .filter(|&n| n > 0)
    });
    egt_core::batch::worker_threads(asked).0
}

/// Size rayon's global pool to `--threads`, where the global pool is about
/// to work (parsing `--rows`, a lone block, `--specs` lines) rather than at
/// the start: built, its idle threads would spin beside the block tasks.
/// (The pool is built once a process; a second build only fails.)
pub(super) fn size_global_pool(requested: Option<usize>) {
    if requested.is_some() {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(batch_threads(requested))
            .build_global();
    }
}

/// How many blocks a thread may be ahead of the writer ([`in_order`]), when
/// blocks are of [`BLOCK`] rows ([`COLUMNAR_BLOCK`] for Parquet and Arrow
/// IPC; 1 measured slower there). Blocks cut short by [`BLOCK_BYTES`] (wide
/// rows, large trains) keep one a thread, as much as the waves before held.
/// (4 and 8 measured no faster than 2, 2026-11-26.)
pub(super) const AHEAD: usize = 2;
