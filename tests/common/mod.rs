//! Helpers shared by the end-to-end tests that drive the `ks-fit` binary (each test crate
//! uses some of them).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `ks-fit` in the crate root: (exit code, stdout, stderr).
pub fn ks_fit(args: &[&str]) -> (i32, String, String) {
    ks_fit_env(args, &[])
}

/// A fresh, empty temporary folder named after the test process and `tag`.
pub fn folder(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("kshell-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// As [`ks_fit`], with extra environment variables.
pub fn ks_fit_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ks-fit"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run ks-fit");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
