//! What the native code generators report, in every build: why code could not
//! be had ([`JitError`] from cranelift, `jit.rs`; [`CcError`] from the system C
//! compiler, `cc.rs`), how a C library came to be ([`CBuild`]), and whether the
//! host fuses multiply-adds, which the interpreter follows so that it agrees
//! with native code bit for bit. Without the `jit` feature (the browser's
//! build, `interpreted.rs`) these are all there is: every compilation fails
//! with them and the interpreter computes everything.

use std::path::PathBuf;

/// Why a tape could not be compiled to native code. The caller falls back to
/// [`Tape::eval`](crate::Tape::eval).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JitError {
    /// Cranelift has no backend for this machine, or refused its flags.
    #[error("no native code generator for this machine: {reason}")]
    UnsupportedHost {
        /// What cranelift said.
        reason: String,
    },
    /// Cranelift failed to compile or link the function.
    #[error("native code generation failed: {message}")]
    Codegen {
        /// What cranelift said.
        message: String,
    },
}

/// Why C could not serve: the caller falls back to cranelift and may say why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CcError {
    /// No compiler was found, or `LAGRANGE_CC=off`.
    #[error("no C compiler: {0}")]
    NoCompiler(String),
    /// The compiler ran and failed.
    #[error("the C compiler failed: {0}")]
    Failed(String),
    /// Files could not be written or the library could not be loaded.
    #[error("{0}")]
    Io(String),
}

/// How a library came to be: the compiler, where it lies, and what it cost.
#[derive(Debug, Clone, PartialEq)]
pub struct CBuild {
    /// The compiler that built it.
    pub compiler: PathBuf,
    /// The shared library.
    pub library: PathBuf,
    /// Seconds spent getting it: compiling, or finding it in the cache and
    /// loading it.
    pub seconds: f64,
    /// Whether it came from the cache.
    pub cached: bool,
}

/// Whether `fma` compiles to one instruction here (elsewhere cranelift would
/// call a library routine).
pub(crate) fn host_has_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("fma");
    #[cfg(target_arch = "aarch64")]
    return true;
    #[allow(unreachable_code)]
    false
}
