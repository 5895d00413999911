//! Compiling several functions on this thread and one helper thread that
//! share the work, without ever waiting for the helper to be scheduled.
//!
//! A short run pays the compile in full, so it is split in two; but handing
//! half of it to a thread and joining it costs up to two milliseconds on a
//! virtual machine whose second CPU is asleep: the thread starts late, and
//! the join sleeps until the kernel wakes the caller again. Here the
//! functions are numbered, and both threads take the next number from one
//! counter until none is left. The calling thread never waits for the
//! helper to start: if it has not started when the work runs out, the
//! caller did all of it and the helper, when it runs, finds nothing to do.
//! When the helper did take a function, the caller spins (it is finishing
//! one function at most) instead of sleeping in a join. The helper is
//! never joined; it ends on its own.

use super::{new_module, Codegen, JitError};
use cranelift_jit::JITModule;
use cranelift_module::FuncId;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

/// The functions one thread compiled, in its own module (finalized): their
/// numbers and ids.
pub(crate) type Part = (JITModule, Vec<(usize, FuncId)>);

/// The helper has not taken any work.
const IDLE: usize = 0;
/// The helper is compiling.
const WORKING: usize = 1;
/// The helper's result is in the slot.
const DONE: usize = 2;
/// The caller finished everything before the helper started; it must not start.
const CLOSED: usize = 3;

struct Shared<D> {
    /// The next function number to take.
    next: AtomicUsize,
    /// One of [`IDLE`], [`WORKING`], [`DONE`], [`CLOSED`].
    helper: AtomicUsize,
    /// The helper's result, set before `helper` becomes [`DONE`].
    slot: Mutex<Option<Result<Option<Part>, JitError>>>,
    count: usize,
    codegen: Codegen,
    define: D,
}

impl<D> Shared<D>
where
    D: Fn(&mut JITModule, usize) -> Result<FuncId, JitError> + Send + Sync + 'static,
{
    fn new(count: usize, codegen: Codegen, define: D) -> Arc<Shared<D>> {
        Arc::new(Shared {
            next: AtomicUsize::new(0),
            helper: AtomicUsize::new(IDLE),
            slot: Mutex::new(None),
            count,
            codegen,
            define,
        })
    }

    /// Starts the helper (when there is more than one function): once
    /// scheduled, unless the caller has closed the work, it takes functions
    /// as [`work`] does and gives its result to `finish`, or an error if it
    /// unwinds first. When no thread can be had, the work is closed and
    /// `false` returned: the caller does it all.
    fn spawn_helper(self: &Arc<Self>, finish: impl FnOnce(Result<Option<Part>, JitError>) + Send + 'static) -> bool {
        if self.count <= 1 {
            return true;
        }
        let theirs = Arc::clone(self);
        let spawned = std::thread::Builder::new().name("lagrange-jit".into()).spawn(move || {
            if theirs.helper.compare_exchange(IDLE, WORKING, Ordering::AcqRel, Ordering::Acquire).is_err() {
                return;
            }
            let mut guard = OnUnwind(Some(finish));
            let result = work(&theirs);
            if let Some(finish) = guard.0.take() {
                finish(result);
            }
        });
        if spawned.is_err() {
            self.helper.store(CLOSED, Ordering::Release);
        }
        spawned.is_ok()
    }
}

/// Gives the helper's `finish` an error if the helper unwinds before it gave
/// its result, so that the caller never waits forever.
struct OnUnwind<F: FnOnce(Result<Option<Part>, JitError>)>(Option<F>);

impl<F: FnOnce(Result<Option<Part>, JitError>)> Drop for OnUnwind<F> {
    fn drop(&mut self) {
        if let Some(finish) = self.0.take() {
            finish(Err(JitError::Codegen { message: "compiler thread panicked".into() }));
        }
    }
}

/// Compiles functions `0..count`, `define(module, i)` declaring and defining
/// function `i` in `module` (a [`new_module`] for `codegen`), on this thread and one
/// helper. Returns the (one or two) finalized modules with the functions each
/// holds. `define` should take the largest functions first (lowest numbers),
/// so that the last one taken, which the caller may wait for, is short.
pub(crate) fn compile_shared<D>(count: usize, codegen: Codegen, define: D) -> Result<Vec<Part>, JitError>
where
    D: Fn(&mut JITModule, usize) -> Result<FuncId, JitError> + Send + Sync + 'static,
{
    let shared = Shared::new(count, codegen, define);
    let theirs = Arc::clone(&shared);
    // Where no thread can be had, this thread does all the work below.
    shared.spawn_helper(move |result| {
        *theirs.slot.lock().unwrap_or_else(PoisonError::into_inner) = Some(result);
        theirs.helper.store(DONE, Ordering::Release);
    });
    let mine = work(&shared);
    let mut parts = Vec::with_capacity(2);
    if shared.helper.compare_exchange(IDLE, CLOSED, Ordering::AcqRel, Ordering::Acquire).is_err() {
        // The helper is working or done: it holds at most the function it took last.
        let mut spins = 0u32;
        while shared.helper.load(Ordering::Acquire) == WORKING {
            spins += 1;
            if spins.is_multiple_of(64) {
                // One CPU only: let the helper run.
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        if shared.helper.load(Ordering::Acquire) == DONE {
            let theirs = shared.slot.lock().unwrap_or_else(PoisonError::into_inner).take();
            if let Some(part) = theirs.expect("set before DONE")? {
                parts.push(part);
            }
        }
    }
    if let Some(part) = mine? {
        parts.push(part);
    }
    Ok(parts)
}

/// The two threads' results in [`compile_shared_then`]: the second to
/// finish hands both to `publish`.
struct Handover<P> {
    parts: Mutex<Vec<Part>>,
    error: Mutex<Option<JitError>>,
    finished: AtomicUsize,
    publish: Mutex<Option<P>>,
}

impl<P: FnOnce(Result<Vec<Part>, JitError>)> Handover<P> {
    /// Adds one thread's result; the second calls `publish` with both.
    fn hand(&self, result: Result<Option<Part>, JitError>) {
        match result {
            Ok(Some(part)) => self.parts.lock().unwrap_or_else(PoisonError::into_inner).push(part),
            Ok(None) => {}
            Err(e) => {
                self.error.lock().unwrap_or_else(PoisonError::into_inner).get_or_insert(e);
            }
        }
        if self.finished.fetch_add(1, Ordering::AcqRel) == 1 {
            let parts = std::mem::take(&mut *self.parts.lock().unwrap_or_else(PoisonError::into_inner));
            let error = self.error.lock().unwrap_or_else(PoisonError::into_inner).take();
            if let Some(publish) = self.publish.lock().unwrap_or_else(PoisonError::into_inner).take() {
                publish(error.map_or(Ok(parts), Err));
            }
        }
    }
}

/// [`compile_shared`] for a caller that has other work to do meanwhile: the
/// two threads share the functions as there, but when none is left to take
/// the caller returns at once instead of waiting for the helper's last one,
/// and whichever thread finishes last hands the finalized modules to
/// `publish` (the caller itself when the helper never started). `publish`
/// is called exactly once, also with an error.
pub(crate) fn compile_shared_then<D, P>(count: usize, codegen: Codegen, define: D, publish: P)
where
    D: Fn(&mut JITModule, usize) -> Result<FuncId, JitError> + Send + Sync + 'static,
    P: FnOnce(Result<Vec<Part>, JitError>) + Send + 'static,
{
    let shared = Shared::new(count, codegen, define);
    let handover = Arc::new(Handover {
        parts: Mutex::new(Vec::with_capacity(2)),
        error: Mutex::new(None),
        finished: AtomicUsize::new(0),
        publish: Mutex::new(Some(publish)),
    });
    let their_handover = Arc::clone(&handover);
    if !shared.spawn_helper(move |result| their_handover.hand(result)) {
        // No thread to be had: this thread does all the work, and hands it alone.
        handover.finished.store(1, Ordering::Release);
    }
    let mine = work(&shared);
    if shared.helper.compare_exchange(IDLE, CLOSED, Ordering::AcqRel, Ordering::Acquire).is_ok() {
        // The helper never started (or could not): this thread has it all.
        handover.finished.store(1, Ordering::Release);
    }
    handover.hand(mine);
}

/// Takes and compiles functions until none is left; `None` if it took none.
fn work<D>(shared: &Shared<D>) -> Result<Option<Part>, JitError>
where
    D: Fn(&mut JITModule, usize) -> Result<FuncId, JitError>,
{
    let mut module: Option<JITModule> = None;
    let mut ids = Vec::new();
    loop {
        let i = shared.next.fetch_add(1, Ordering::AcqRel);
        if i >= shared.count {
            break;
        }
        let m = match &mut module {
            Some(m) => m,
            None => module.insert(new_module(shared.codegen)?),
        };
        ids.push((i, (shared.define)(m, i)?));
    }
    match module {
        None => Ok(None),
        Some(mut m) => {
            m.finalize_definitions().map_err(super::codegen)?;
            Ok(Some((m, ids)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every number is compiled exactly once, whichever thread takes it.
    #[test]
    fn every_function_is_compiled_once() {
        for count in [1, 2, 7, 40] {
            let parts = compile_shared(count, Codegen::Quick, declare).unwrap();
            let mut seen: Vec<usize> = parts.iter().flat_map(|(_, ids)| ids.iter().map(|&(i, _)| i)).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..count).collect::<Vec<_>>());
            assert!(parts.len() <= 2);
        }
    }

    /// An error on either thread comes back to the caller.
    #[test]
    fn errors_reach_the_caller() {
        let result = compile_shared(30, Codegen::Quick, |m, i| {
            if i == 17 {
                Err(JitError::Codegen { message: "no".into() })
            } else {
                declare(m, i)
            }
        });
        assert!(matches!(result, Err(JitError::Codegen { .. })));
    }

    /// A function `() -> ()` named after `i`.
    fn declare(m: &mut JITModule, i: usize) -> Result<FuncId, JitError> {
        use cranelift_codegen::ir::InstBuilder;
        use cranelift_module::{Linkage, Module};
        let sig = m.make_signature();
        let id = m.declare_function(&format!("f{i}"), Linkage::Local, &sig).map_err(super::super::codegen)?;
        super::super::define_function(m, id, &sig, |_, mut b, _| {
            b.ins().return_(&[]);
            Ok(b)
        })?;
        Ok(id)
    }
}
