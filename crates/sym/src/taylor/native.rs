//! The native code of a Taylor program, and the one place that picks how it
//! is made: cranelift (`cranelift.rs`) or the system C compiler (`c.rs`). The
//! tape (`tape.rs`) holds a [`NativeTaylor`] and runs it; built without the
//! `jit` feature (the browser's build) there is none, and every constructor
//! fails with the reason, so the tape keeps its interpreter.

#[cfg(feature = "jit")]
pub(super) use compiled::NativeTaylor;
#[cfg(not(feature = "jit"))]
pub(super) use none::NativeTaylor;

/// Tapes whose unrolled code would exceed this many multiply-adds (over all
/// orders and lanes) stay interpreted: compiling takes about a microsecond per
/// multiply-add, which a run must win back.
pub(crate) const NATIVE_MAX_WORK: usize = 60_000;

#[cfg(feature = "jit")]
mod compiled {
    #![allow(unsafe_code)]
    // Calling native code can only be done through a raw function pointer; see
    // `jit.rs` for the same pattern. The unsafe blocks: the pointer casts in
    // `NativeTaylor::assemble`, the calls in `run` and `run_all`, and the release
    // of the code in `Drop`.

    use super::super::program::{Instruction, SecondOrderLayout};
    use super::super::{c, cranelift};
    use crate::cc::{self, CBuild, CLibrary, CcError};
    use crate::jit::shared::Part;
    use crate::jit::JitError;
    use crate::native::host_has_fma;
    use cranelift_jit::JITModule;
    use std::sync::{Mutex, PoisonError};

    /// `(coefficients, series)`: the tape's buffer, and the caller's order-major
    /// series of a second-order expansion (null for the tape's orders alone).
    type OrderFn = unsafe extern "C" fn(coef: *mut f64, series: *mut f64);

    /// Orders `0..=p` of a Taylor tape as native functions. Shared by the clones
    /// of a tape (one compilation serves an ensemble's workers).
    pub(crate) struct NativeTaylor {
        /// Own the code the functions point into; taken only in `Drop`.
        modules: Mutex<Vec<JITModule>>,
        /// Or the C library that holds it (`c.rs`); dropped after the
        /// functions, as fields drop in order.
        library: Option<CLibrary>,
        funcs: Vec<OrderFn>,
        /// The length of the coefficient buffer the functions address.
        len: usize,
        /// The length of the series a second-order expansion writes (orders
        /// `1..=p` of `[y, y']`, order-major); 0 for the tape's orders alone.
        series_len: usize,
    }

    impl std::fmt::Debug for NativeTaylor {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.debug_struct("NativeTaylor").field("orders", &self.funcs.len()).finish_non_exhaustive()
        }
    }

    impl NativeTaylor {
        /// Compiles the whole expansion of a linearly implicit second-order
        /// system `A y'' = b` (run it with
        /// [`run_all`](Self::run_all)): orders `0..p` of the tape, each followed by
        /// the coupling that yields the state's next order, one function per
        /// order, compiled on two threads ([`compile_shared`]: compiling costs
        /// more than a thousand steps of a small system).
        pub(crate) fn second_order<const L: usize>(
            program: Vec<(u32, Instruction)>,
            order: usize,
            layout: SecondOrderLayout,
            buffer_len: usize,
        ) -> Result<NativeTaylor, JitError> {
            let series_len = (order + 1) * 2 * layout.n * L;
            let parts = cranelift::second_order::<L>(program, order, layout)?;
            Ok(NativeTaylor::assemble(parts, order, |i| order - 1 - i, buffer_len, series_len))
        }

        /// [`second_order`](Self::second_order) for a caller that steps on
        /// meanwhile ([`compile_shared_then`]): returns when no function is left
        /// for this thread to compile; `publish` gets the code (or the error)
        /// from whichever thread finishes last. The helper gives up as soon as
        /// `wanted()` turns false.
        pub(crate) fn second_order_then<const L: usize>(
            program: Vec<(u32, Instruction)>,
            order: usize,
            layout: SecondOrderLayout,
            buffer_len: usize,
            wanted: impl Fn() -> bool + Send + Sync + 'static,
            publish: impl FnOnce(Result<NativeTaylor, JitError>) + Send + 'static,
        ) {
            let series_len = (order + 1) * 2 * layout.n * L;
            cranelift::second_order_then::<L>(program, order, layout, wanted, move |parts| {
                publish(
                    parts.map(|parts| NativeTaylor::assemble(parts, order, |i| order - 1 - i, buffer_len, series_len)),
                )
            });
        }

        /// Compiles every order of `program`, one function each, on two threads.
        pub(crate) fn new<const L: usize>(
            program: &[(u32, Instruction)],
            order: usize,
            buffer_len: usize,
        ) -> Result<NativeTaylor, JitError> {
            let parts = cranelift::orders::<L>(program.to_vec(), order)?;
            Ok(NativeTaylor::assemble(parts, order + 1, |i| order - i, buffer_len, 0))
        }

        /// The functions of `parts` by order (`order_of` maps a function's number
        /// to its order), and the modules that own them.
        fn assemble(
            parts: Vec<Part>,
            count: usize,
            order_of: impl Fn(usize) -> usize,
            len: usize,
            series_len: usize,
        ) -> NativeTaylor {
            let mut funcs: Vec<Option<OrderFn>> = vec![None; count];
            let mut modules = Vec::with_capacity(parts.len());
            for (module, ids) in parts {
                for (i, id) in ids {
                    let code = module.get_finalized_function(id);
                    // SAFETY: `code` is the entry of a function just defined with
                    // signature `(ptr, ptr) -> ()` in the host's default calling
                    // convention (`extern "C"` on every host cranelift-native
                    // supports); the module owning it lives as long as `self`.
                    funcs[order_of(i)] = Some(unsafe { std::mem::transmute::<*const u8, OrderFn>(code) });
                }
                modules.push(module);
            }
            let funcs = funcs.into_iter().map(|f| f.expect("compile_shared compiles every function")).collect();
            NativeTaylor { modules: Mutex::new(modules), library: None, funcs, len, series_len }
        }

        /// The whole expansion of a second-order system, like
        /// [`second_order`](Self::second_order), compiled by the system C
        /// compiler at the machine's vector width (`cc.rs`, `c.rs`).
        pub(crate) fn second_order_c<const L: usize>(
            program: &[(u32, Instruction)],
            order: usize,
            layout: &SecondOrderLayout,
            buffer_len: usize,
        ) -> Result<NativeTaylor, CcError> {
            let source = c::second_order::<L>(program, order, layout, host_has_fma());
            let series_len = (order + 1) * 2 * layout.n * L;
            NativeTaylor::from_c(&source, buffer_len, series_len)
        }

        /// Every order of `program`, like [`new`](Self::new), compiled by the
        /// system C compiler.
        pub(crate) fn orders_c<const L: usize>(
            program: &[(u32, Instruction)],
            order: usize,
            buffer_len: usize,
        ) -> Result<NativeTaylor, CcError> {
            let source = c::orders::<L>(program, order, host_has_fma());
            NativeTaylor::from_c(&source, buffer_len, 0)
        }

        fn from_c(source: &c::CSource, len: usize, series_len: usize) -> Result<NativeTaylor, CcError> {
            let files = std::thread::available_parallelism().map_or(1, |n| n.get()).min(4);
            let library = cc::build(&source.files(files))?;
            let funcs = (0..source.parts.len()).map(|i| library.get(&c::part_name(i))).collect::<Result<_, _>>()?;
            Ok(NativeTaylor { modules: Mutex::new(Vec::new()), library: Some(library), funcs, len, series_len })
        }

        /// How the code was built: by the C compiler (and how), or by cranelift (None).
        pub(crate) fn c_build(&self) -> Option<&CBuild> {
            self.library.as_ref().map(|l| &l.build)
        }

        /// Runs the function of order `k` on the coefficient buffer (the tape's
        /// orders, [`new`](Self::new)).
        ///
        /// # Panics
        ///
        /// When `coef` is not the length the code was compiled for, `k` is above
        /// the order, or the functions are a second-order expansion's.
        pub(crate) fn run(&self, k: usize, coef: &mut [f64]) {
            assert_eq!(coef.len(), self.len, "NativeTaylor::run: wrong buffer length");
            assert_eq!(self.series_len, 0, "NativeTaylor::run: a second-order expansion writes a series");
            let f = self.funcs[k];
            // SAFETY: the function reads and writes `coef[i]` only for indices
            // `(slot * (order + 1) + j) * L + lane` of slots, orders and lanes of
            // the tape it was compiled from, all below `self.len`, which was just
            // checked; the slice is valid and exclusively borrowed. Functions of
            // the tape's orders never touch the second pointer (only `couple`,
            // of second-order expansions, writes it). The code is alive while
            // `self` is, calls only the safe wrappers of `jit.rs`, and never
            // unwinds.
            unsafe { f(coef.as_mut_ptr(), std::ptr::null_mut()) }
        }

        /// Runs every function of a second-order expansion in turn
        /// ([`second_order`](Self::second_order)), writing orders `1..=p` of
        /// `[y, y']` into `series` (order-major, `L` lanes each; order 0 is the
        /// caller's).
        ///
        /// # Panics
        ///
        /// When `coef` or `series` is not the length the code was compiled for.
        pub(crate) fn run_all(&self, coef: &mut [f64], series: &mut [f64]) {
            assert_eq!(coef.len(), self.len, "NativeTaylor::run_all: wrong buffer length");
            assert!(self.series_len > 0, "NativeTaylor::run_all: not a second-order expansion");
            assert_eq!(series.len(), self.series_len, "NativeTaylor::run_all: wrong series length");
            for &f in &self.funcs {
                // SAFETY: as in `run` for `coef`; the function writes `series[i]`
                // only for `i = (order·2n + component)·L + lane` with order ≤ p,
                // component < 2n and lane < L, all below `self.series_len`, which
                // was just checked, and the slice is valid and exclusively
                // borrowed.
                unsafe { f(coef.as_mut_ptr(), series.as_mut_ptr()) }
            }
        }
    }

    impl Drop for NativeTaylor {
        fn drop(&mut self) {
            let modules = std::mem::take(self.modules.get_mut().unwrap_or_else(PoisonError::into_inner));
            for module in modules {
                // SAFETY: the functions are only called through `run` and
                // `run_all`, which need `&self`; `drop` has `&mut self`, so none is
                // running, and none can be called afterwards.
                unsafe { module.free_memory() }
            }
        }
    }
}

/// What stands for native code in a build without the `jit` feature.
#[cfg(not(feature = "jit"))]
mod none {
    use super::super::program::{Instruction, SecondOrderLayout};
    use crate::native::{CBuild, CcError, JitError};

    fn no_jit() -> JitError {
        JitError::UnsupportedHost { reason: "built without the `jit` feature".into() }
    }

    fn no_cc() -> CcError {
        CcError::NoCompiler("built without the `jit` feature".into())
    }

    /// Native Taylor code: none in this build, so no value of this type.
    #[derive(Debug)]
    pub(crate) enum NativeTaylor {}

    impl NativeTaylor {
        pub(crate) fn second_order<const L: usize>(
            _program: Vec<(u32, Instruction)>,
            _order: usize,
            _layout: SecondOrderLayout,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, JitError> {
            Err(no_jit())
        }

        /// Publishes the failure at once, on this thread.
        pub(crate) fn second_order_then<const L: usize>(
            _program: Vec<(u32, Instruction)>,
            _order: usize,
            _layout: SecondOrderLayout,
            _buffer_len: usize,
            _wanted: impl Fn() -> bool + Send + Sync + 'static,
            publish: impl FnOnce(Result<NativeTaylor, JitError>) + Send + 'static,
        ) {
            publish(Err(no_jit()))
        }

        pub(crate) fn new<const L: usize>(
            _program: &[(u32, Instruction)],
            _order: usize,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, JitError> {
            Err(no_jit())
        }

        pub(crate) fn second_order_c<const L: usize>(
            _program: &[(u32, Instruction)],
            _order: usize,
            _layout: &SecondOrderLayout,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, CcError> {
            Err(no_cc())
        }

        pub(crate) fn orders_c<const L: usize>(
            _program: &[(u32, Instruction)],
            _order: usize,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, CcError> {
            Err(no_cc())
        }

        pub(crate) fn c_build(&self) -> Option<&CBuild> {
            match *self {}
        }

        pub(crate) fn run(&self, _k: usize, _coef: &mut [f64]) {
            match *self {}
        }

        pub(crate) fn run_all(&self, _coef: &mut [f64], _series: &mut [f64]) {
            match *self {}
        }
    }
}
