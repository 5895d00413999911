//! What the native code generators report, in every build: why code could not
//! be had ([`JitError`] from cranelift, `jit.rs`; [`CcError`] from the system C
//! compiler, `cc.rs`), how a C library came to be ([`CBuild`]), and whether the
//! host fuses multiply-adds, which the interpreter follows so that it agrees
//! with native code bit for bit. Without the `jit` feature (the browser's
//! build, `interpreted.rs`) these are all there is: every compilation fails
//! with them and the interpreter computes everything.

use std::path::PathBuf;

/// Tapes longer than this are compiled with the single-pass register
/// allocator (`jit.rs`'s `Codegen::Quick`; declared here, in every build, for
/// the callers that size their work by it). The backtracking allocator's time grows
/// faster than linearly with the values live across a long function: the
/// right-hand side of a chain of forty rods (about 60 000 instructions)
/// spent 8 of its run's 10 s allocating registers. From 4096 instructions on
/// (the articulated-body kernels of 50-link chains and humanoids, 3 000 to
/// 17 000) the quick allocator's code runs as fast (0.99× and 1.03× over 200 s
/// of a 50-link and a 20-rod chain) and whole runs to t = 10 take 0.81× to
/// 0.97× the time, the compile being most of the difference.
pub const QUICK_MIN_OPS: usize = 4_096;

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
