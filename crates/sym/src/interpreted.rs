//! The build without the `jit` feature (the browser's, `wasm32-unknown-unknown`,
//! where neither cranelift nor a C compiler can run): the native code
//! generators' entry points, each failing with the reason, so that every caller
//! keeps the interpreter ([`crate::Tape::eval`], the Taylor tape's own loops)
//! it falls back to anyway. The interpreter is the reference the native code
//! agrees with bit for bit, so results do not change; only speed does.

/// What stands for `jit.rs`: [`Compiled`] that never compiles.
pub(crate) mod jit {
    use crate::eval::Tape;
    pub(crate) use crate::native::JitError;

    /// A tape compiled to native code: never, in this build
    /// ([`Compiled::new`] says why), so there is no value of this type.
    #[derive(Debug)]
    pub enum Compiled {}

    impl Compiled {
        /// Fails: this build has no code generator (the `jit` feature is off).
        /// The caller keeps using [`Tape::eval`].
        pub fn new(_tape: &Tape) -> Result<Compiled, JitError> {
            Err(JitError::UnsupportedHost { reason: "built without the `jit` feature".into() })
        }

        /// The number of inputs expected by [`Compiled::eval`].
        pub fn n_inputs(&self) -> usize {
            match *self {}
        }

        /// The number of outputs written by [`Compiled::eval`].
        pub fn n_outputs(&self) -> usize {
            match *self {}
        }

        /// The number of tape instructions this function was compiled from.
        pub fn len(&self) -> usize {
            match *self {}
        }

        /// True when the tape had no instruction.
        pub fn is_empty(&self) -> bool {
            match *self {}
        }

        /// Evaluates every root, as [`Tape::eval`] does.
        pub fn eval(&self, _inputs: &[f64], _outputs: &mut [f64]) {
            match *self {}
        }
    }
}

/// What stands for `taylor_jit.rs`: native Taylor code that never compiles.
pub(crate) mod taylor_jit {
    use crate::native::{CBuild, CcError, JitError};
    use crate::taylor::{SecondOrderLayout, TaylorTape, T};

    /// As in `taylor_jit.rs`: past this, tapes stay interpreted there too.
    pub(crate) const NATIVE_MAX_WORK: usize = 60_000;

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
            _program: Vec<(u32, T)>,
            _order: usize,
            _layout: SecondOrderLayout,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, JitError> {
            Err(no_jit())
        }

        /// Publishes the failure at once, on this thread.
        pub(crate) fn second_order_then<const L: usize>(
            _program: Vec<(u32, T)>,
            _order: usize,
            _layout: SecondOrderLayout,
            _buffer_len: usize,
            _wanted: impl Fn() -> bool + Send + Sync + 'static,
            publish: impl FnOnce(Result<NativeTaylor, JitError>) + Send + 'static,
        ) {
            publish(Err(no_jit()))
        }

        pub(crate) fn new<const L: usize>(_tape: &TaylorTape<L>) -> Result<NativeTaylor, JitError> {
            Err(no_jit())
        }

        pub(crate) fn second_order_c<const L: usize>(
            _program: &[(u32, T)],
            _order: usize,
            _layout: &SecondOrderLayout,
            _buffer_len: usize,
        ) -> Result<NativeTaylor, CcError> {
            Err(no_cc())
        }

        pub(crate) fn orders_c<const L: usize>(_tape: &TaylorTape<L>) -> Result<NativeTaylor, CcError> {
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

/// What stands for `cc.rs`: no C compiler.
pub(crate) mod cc {
    use crate::native::CcError;
    use std::path::PathBuf;

    /// The compiler to use: none in this build.
    pub fn compiler() -> Result<PathBuf, CcError> {
        Err(CcError::NoCompiler("built without the `jit` feature".into()))
    }
}
