//! The order a sweep's rows leave in: jobs (runs of consecutive grid points)
//! go to worker threads in grid order, and their results come back to the
//! calling thread in that same order, with at most `window` jobs taken but not
//! yet handed back. Memory is O(window × job) whatever the grid's size, and no
//! thread waits at a barrier: a worker takes the next job as soon as it has
//! finished one, unless the job at the head of the line is that far behind.
//!
//! Enter at [`ordered`]. Stopping is cooperative: a `stop` that turns true (a
//! signal), or an `emit` that breaks (a write that failed), halts the workers
//! between jobs; a job checks the halt itself (through the flag it is given)
//! and may give up, and nothing after the first job not finished is emitted.

use std::ops::ControlFlow;
#[cfg(feature = "parallel")]
use std::{
    collections::BTreeMap,
    panic::{catch_unwind, resume_unwind, AssertUnwindSafe},
    sync::atomic::{AtomicBool, Ordering},
    sync::{Condvar, Mutex, MutexGuard},
    thread,
    time::Duration,
};

/// How often the calling thread looks at `stop` while it waits for the job at
/// the head of the line: a signal is noticed within this time.
#[cfg(feature = "parallel")]
const POLL: Duration = Duration::from_millis(20);

/// The shape of the work: how many jobs, on how many threads, how far ahead.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(not(feature = "parallel"), allow(dead_code))]
pub(crate) struct Plan {
    /// Jobs, numbered `0..jobs` in the order their results are emitted.
    pub jobs: usize,
    /// Worker threads (at least 1).
    pub threads: usize,
    /// Most jobs taken but not yet emitted (at least 1).
    pub window: usize,
}

/// How [`ordered`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum End {
    /// Every job's result was emitted.
    Finished,
    /// `stop` turned true or `emit` broke: a prefix of the results was emitted.
    Stopped,
}

/// What the workers and the emitter share.
#[cfg(feature = "parallel")]
struct Line<R> {
    /// The next job to hand out.
    next: usize,
    /// Jobs emitted so far (the head of the line is job `emitted`).
    emitted: usize,
    /// Finished jobs waiting for their turn; `None` for a job given up.
    done: BTreeMap<usize, Option<R>>,
}

#[cfg(feature = "parallel")]
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A worker that panicked leaves consistent data (its job is marked given
    // up before the panic goes on); the panic itself is re-raised by the scope.
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Runs `work(state, job, halted)` for every job on `plan.threads` threads, each
/// with its own `state` from `init`, and calls `emit` with the results in job
/// order on the calling thread. `work` returns `None` when it gives up because
/// `halted()` turned true. `stop` is looked at by every thread; it must stay
/// true once it is. Without the `parallel` feature, [`in_turn`].
#[cfg(feature = "parallel")]
pub(crate) fn ordered<S, R: Send>(
    plan: Plan,
    init: impl Fn() -> S + Sync,
    work: impl Fn(&mut S, usize, &dyn Fn() -> bool) -> Option<R> + Sync,
    stop: &(dyn Fn() -> bool + Sync),
    mut emit: impl FnMut(R) -> ControlFlow<()>,
) -> Result<End, std::io::Error> {
    debug_assert!(plan.threads >= 1 && plan.window >= 1);
    let line = Mutex::new(Line { next: 0, emitted: 0, done: BTreeMap::new() });
    let changed = Condvar::new();
    let halt = AtomicBool::new(false);
    let halted = || halt.load(Ordering::Relaxed) || stop();
    let worker = || {
        let mut state = init();
        loop {
            let job = {
                let mut l = lock(&line);
                loop {
                    if halted() || l.next >= plan.jobs {
                        return;
                    }
                    if l.next < l.emitted + plan.window {
                        l.next += 1;
                        break l.next - 1;
                    }
                    l = changed.wait(l).unwrap_or_else(|p| p.into_inner());
                }
            };
            // A job that panics is marked given up before the panic goes on, so
            // that the emitter stops there instead of waiting for it.
            let (result, panic) = match catch_unwind(AssertUnwindSafe(|| work(&mut state, job, &halted))) {
                Ok(result) => (result, None),
                Err(panic) => (None, Some(panic)),
            };
            let given_up = result.is_none();
            lock(&line).done.insert(job, result);
            changed.notify_all();
            if let Some(panic) = panic {
                resume_unwind(panic);
            }
            if given_up {
                return;
            }
        }
    };
    thread::scope(|scope| {
        let mut spawned = Ok(());
        for k in 0..plan.threads {
            if let Err(e) = thread::Builder::new().name(format!("sweep-{k}")).spawn_scoped(scope, worker) {
                spawned = Err(e);
                break;
            }
        }
        let end = match spawned {
            Ok(()) => emit_in_order(plan.jobs, &line, &changed, stop, &mut emit),
            Err(_) => End::Stopped,
        };
        // Halt the workers (a stop, a broken emit, or no more jobs) and wake
        // those waiting for room in the window.
        {
            let _l = lock(&line);
            halt.store(true, Ordering::Relaxed);
        }
        changed.notify_all();
        spawned.map(|()| end)
    })
}

/// [`ordered`] without threads (the browser's build): every job in turn on
/// the calling thread, with one `state`, each result emitted as it is made.
/// The same results in the same order, since a job's result never depends on
/// the thread that computed it.
#[cfg(not(feature = "parallel"))]
pub(crate) fn ordered<S, R: Send>(
    plan: Plan,
    init: impl Fn() -> S + Sync,
    work: impl Fn(&mut S, usize, &dyn Fn() -> bool) -> Option<R> + Sync,
    stop: &(dyn Fn() -> bool + Sync),
    emit: impl FnMut(R) -> ControlFlow<()>,
) -> Result<End, std::io::Error> {
    Ok(in_turn(plan, init, work, stop, emit))
}

/// Every job in turn on the calling thread; what [`ordered`] is without the
/// `parallel` feature (and tested as such on every build).
#[cfg_attr(feature = "parallel", allow(dead_code))]
fn in_turn<S, R>(
    plan: Plan,
    init: impl Fn() -> S,
    work: impl Fn(&mut S, usize, &dyn Fn() -> bool) -> Option<R>,
    stop: &dyn Fn() -> bool,
    mut emit: impl FnMut(R) -> ControlFlow<()>,
) -> End {
    let mut state = init();
    for job in 0..plan.jobs {
        if stop() {
            return End::Stopped;
        }
        let Some(result) = work(&mut state, job, stop) else {
            return End::Stopped;
        };
        if emit(result).is_break() {
            return End::Stopped;
        }
    }
    End::Finished
}

/// The calling thread's part: emits the finished jobs in order as they come.
#[cfg(feature = "parallel")]
fn emit_in_order<R>(
    jobs: usize,
    line: &Mutex<Line<R>>,
    changed: &Condvar,
    stop: &(dyn Fn() -> bool + Sync),
    emit: &mut impl FnMut(R) -> ControlFlow<()>,
) -> End {
    let mut l = lock(line);
    loop {
        if l.emitted == jobs {
            return End::Finished;
        }
        let head = l.emitted;
        match l.done.remove(&head) {
            Some(Some(result)) => {
                l.emitted += 1;
                drop(l);
                changed.notify_all();
                if stop() || emit(result).is_break() {
                    return End::Stopped;
                }
                l = lock(line);
            }
            Some(None) => return End::Stopped,
            None => {
                if stop() {
                    return End::Stopped;
                }
                l = changed.wait_timeout(l, POLL).unwrap_or_else(|p| p.into_inner()).0;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::thread;
    use std::time::Duration;

    #[track_caller]
    fn check(plan: Plan, stop_after: Option<usize>, expect_end: End, expect: &[usize]) {
        let emitted = AtomicUsize::new(0);
        let stop = || stop_after.is_some_and(|n| emitted.load(Ordering::Relaxed) >= n);
        let taken = AtomicUsize::new(0);
        let mut got = Vec::new();
        let end = ordered(
            plan,
            || (),
            |(), job, _halted| {
                taken.fetch_add(1, Ordering::Relaxed);
                // Later jobs finish first: the order comes from the line, not the clock.
                thread::sleep(Duration::from_micros(50 * (job % 3) as u64));
                Some(job * 10)
            },
            &stop,
            |r| {
                got.push(r / 10);
                emitted.fetch_add(1, Ordering::Relaxed);
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        assert_eq!((end, got.as_slice()), (expect_end, expect));
        // Nothing runs far past what was emitted.
        assert!(taken.load(Ordering::Relaxed) <= got.len() + plan.window + plan.threads, "{taken:?}");
    }

    #[test]
    fn results_come_in_job_order_and_stop_leaves_a_prefix() {
        let all: Vec<usize> = (0..40).collect();
        check(Plan { jobs: 40, threads: 3, window: 4 }, None, End::Finished, &all);
        check(Plan { jobs: 40, threads: 1, window: 1 }, None, End::Finished, &all);
        check(Plan { jobs: 0, threads: 2, window: 2 }, None, End::Finished, &[]);
        check(Plan { jobs: 40, threads: 3, window: 4 }, Some(7), End::Stopped, &all[..7]);
    }

    #[test]
    fn a_job_given_up_ends_the_line_there() {
        let mut got = Vec::new();
        let end = ordered(
            Plan { jobs: 10, threads: 2, window: 3 },
            || (),
            |(), job, _| (job != 4).then_some(job),
            &|| false,
            |r| {
                got.push(r);
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        assert_eq!((end, got), (End::Stopped, vec![0, 1, 2, 3]));
    }

    #[test]
    fn an_emit_that_breaks_halts_the_workers() {
        let mut got = Vec::new();
        let end = ordered(
            Plan { jobs: 1000, threads: 2, window: 2 },
            || (),
            |(), job, _| Some(job),
            &|| false,
            |r| {
                got.push(r);
                if r == 5 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        )
        .unwrap();
        assert_eq!((end, got), (End::Stopped, (0..6).collect::<Vec<_>>()));
    }

    /// The path of the build without threads, run on every build: what the
    /// threads emit, job by job, where they finish, stop or give up.
    #[test]
    fn in_turn_emits_what_the_threads_emit() {
        let plan = Plan { jobs: 30, threads: 3, window: 4 };
        for give_up in [None, Some(0), Some(17)] {
            for stop_at in [None, Some(0), Some(9)] {
                let work = |(): &mut (), job: usize, _: &dyn Fn() -> bool| (Some(job) != give_up).then_some(job * job);
                let run = |threads: bool| {
                    let mut got = Vec::new();
                    let emit = |r| {
                        got.push(r);
                        if Some(got.len()) == stop_at.map(|n| n + 1) {
                            ControlFlow::Break(())
                        } else {
                            ControlFlow::Continue(())
                        }
                    };
                    let end = if threads {
                        ordered(plan, || (), work, &|| false, emit).unwrap()
                    } else {
                        in_turn(plan, || (), work, &|| false, emit)
                    };
                    (end, got)
                };
                assert_eq!(run(false), run(true), "give up at {give_up:?}, stop at {stop_at:?}");
            }
        }
    }
}
