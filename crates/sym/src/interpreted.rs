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

/// What stands for `cc.rs`: no C compiler.
pub(crate) mod cc {
    use crate::native::CcError;
    use std::path::PathBuf;

    /// The compiler to use: none in this build.
    pub fn compiler() -> Result<PathBuf, CcError> {
        Err(CcError::NoCompiler("built without the `jit` feature".into()))
    }
}
