//! Which code runs a sweep's lock-step batches: the system C compiler's
//! (compiled once, then found in the cache), or cranelift's where there is no
//! compiler or it fails. The rows are the same bits whichever ran, and the
//! summary says which, with the compile time apart from the runs'.

use crate::common::{repo_root, scratch};
use std::path::Path;
use std::process::Command;

/// `lagrange sweep` of a small double-pendulum map with `env` set, into
/// `out`; its stderr.
fn sweep(out: &Path, env: &[(&str, &str)]) -> String {
    let model = repo_root().join("examples/double_pendulum.toml");
    let output = Command::new(env!("CARGO_BIN_EXE_lagrange"))
        .args(["sweep", model.to_str().unwrap(), "--until", "2", "--grid", "a=-3:3:5,b=-3:3:4", "--threads", "2"])
        .arg("--out")
        .arg(out)
        .envs(env.iter().copied())
        .env_remove("CC")
        .output()
        .expect("run lagrange");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{env:?}: {stderr}");
    stderr
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_c_compilers_code_is_cached_and_gives_cranelifts_rows() {
    let cache = scratch("sweep-code", "cache");
    let _ = std::fs::remove_dir_all(&cache);
    let cache = cache.to_str().unwrap();
    let (c, again, off, failing, missing) = (
        scratch("sweep-code", "c.csv"),
        scratch("sweep-code", "again.csv"),
        scratch("sweep-code", "off.csv"),
        scratch("sweep-code", "failing.csv"),
        scratch("sweep-code", "missing.csv"),
    );

    let first = sweep(&c, &[("LAGRANGE_CACHE_DIR", cache)]);
    assert!(first.contains("was compiled by") && first.contains("cached in"), "{first}");
    assert!(first.contains(cache), "{first}");
    let second = sweep(&again, &[("LAGRANGE_CACHE_DIR", cache)]);
    assert!(second.contains("came from the cache"), "{second}");

    let cranelift = sweep(&off, &[("LAGRANGE_CACHE_DIR", cache), ("LAGRANGE_CC", "off")]);
    assert!(cranelift.contains("compiled by cranelift") && cranelift.contains("LAGRANGE_CC is off"), "{cranelift}");
    let failed = sweep(&failing, &[("LAGRANGE_CACHE_DIR", cache), ("LAGRANGE_CC", "/bin/false")]);
    assert!(failed.contains("compiled by cranelift") && failed.contains("the C compiler failed"), "{failed}");
    let absent = sweep(&missing, &[("LAGRANGE_CACHE_DIR", cache), ("LAGRANGE_CC", "/no/such/cc")]);
    assert!(absent.contains("compiled by cranelift") && absent.contains("/no/such/cc is not a file"), "{absent}");

    // The same rows, bit for bit, whichever code computed them.
    let want = bytes(&c);
    for other in [&again, &off, &failing, &missing] {
        assert!(bytes(other) == want, "{} differs from {}", other.display(), c.display());
    }
}
