//! Output locks: a command holds `.NAME.ks-lock` beside each output `NAME` while it runs, so two
//! commands never write the same file or folder at once. The lock is created with `create_new`
//! (exclusive), holds the pid of its owner and is removed when the command ends. A lock whose
//! pid no longer runs (left by a command that was killed) is stale and taken over;
//! where running processes cannot be listed (no `/proc`), every lock counts as held.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Suffix of a lock file's name (`.NAME` + this, beside the output `NAME`).
pub const LOCK_SUFFIX: &str = ".ks-lock";

/// A held lock; dropping it removes the file.
pub struct OutputLock {
    path: PathBuf,
}

impl OutputLock {
    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The lock file of `output`: `.NAME.ks-lock` in the output's folder, after resolving the
/// folders that exist (so `./x` and `x` share one lock). Below the deepest existing folder the
/// rest of the path is folded into the name (`a/b` under an existing `d` gives `d/.a_b.ks-lock`).
pub fn lock_path(output: &Path) -> Option<PathBuf> {
    let absolute = std::path::absolute(output).ok()?;
    let mut base = absolute.clone();
    let mut rest: Vec<String> = Vec::new();
    loop {
        let name = base.file_name()?.to_string_lossy().into_owned();
        let parent = base.parent()?.to_path_buf();
        rest.push(name);
        if let Ok(dir) = parent.canonicalize() {
            rest.reverse();
            return Some(dir.join(format!(".{}{LOCK_SUFFIX}", rest.join("_"))));
        }
        base = parent;
    }
}

/// Whether process `pid` runs; `None` where this cannot be told (no `/proc`).
fn running(pid: u32) -> Option<bool> {
    if !Path::new("/proc/self").exists() {
        return None;
    }
    Some(Path::new(&format!("/proc/{pid}")).exists())
}

/// Takes the lock of `output` (given by `flag`), or says which process holds it.
pub fn take(flag: &str, output: &Path) -> Result<OutputLock, String> {
    let shown = output.display();
    let path = lock_path(output)
        .ok_or_else(|| format!("{flag} {shown}: cannot name a lock file beside it"))?;
    // twice at most: a stale lock is removed once and the lock taken afresh
    for _ in 0..2 {
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
        {
            Ok(mut f) => {
                let lock = OutputLock { path };
                writeln!(f, "{}", std::process::id()).map_err(|e| {
                    format!("{flag} {shown}: cannot write {}: {e}", lock.path.display())
                })?;
                return Ok(lock);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                let pid = text.trim().parse::<u32>().ok();
                match pid.map(|p| (p, running(p))) {
                    Some((p, Some(false))) => {
                        eprintln!(
                            "ks-fit: note: {}: removing a stale lock (pid {p} no longer runs)",
                            path.display()
                        );
                        let _ = std::fs::remove_file(&path);
                    }
                    Some((p, _)) => {
                        return Err(format!(
                            "{flag} {shown}: another ks-fit (pid {p}) is writing it and holds the lock {}; wait for it to end, or remove the lock if that process is not ks-fit",
                            path.display()
                        ))
                    }
                    None => {
                        return Err(format!(
                            "{flag} {shown}: the lock {} exists and names no process; another ks-fit may be writing it (remove the lock if none is)",
                            path.display()
                        ))
                    }
                }
            }
            Err(e) => {
                return Err(format!(
                    "{flag} {shown}: cannot create the lock {}: {e}",
                    path.display()
                ))
            }
        }
    }
    Err(format!(
        "{flag} {shown}: cannot take the lock {}",
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lock_is_exclusive_and_removed_on_drop() {
        let dir = std::env::temp_dir().join(format!("ks-fit-lock-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("m.toml");
        let lock = take("-o", &out).unwrap();
        assert_eq!(
            lock.path(),
            dir.canonicalize().unwrap().join(".m.toml.ks-lock")
        );
        // held by a running process (this one): refused, naming the pid and the lock file
        let err = take("-o", &dir.join(".").join("m.toml"))
            .err()
            .unwrap_or_default();
        assert!(
            err.contains(&format!("pid {}", std::process::id())) && err.contains(".m.toml.ks-lock"),
            "{err}"
        );
        drop(lock);
        assert!(!dir.join(".m.toml.ks-lock").exists());
        // a folder below a missing one: the lock sits in the deepest folder that exists
        let deep = lock_path(&dir.join("a/b")).unwrap();
        assert_eq!(deep, dir.canonicalize().unwrap().join(".a_b.ks-lock"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
