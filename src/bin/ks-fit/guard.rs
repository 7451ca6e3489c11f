//! Output paths checked before any work starts: an output never replaces one of the command's
//! inputs or a dataset folder (unless `--force`), its folder exists and is writable, and a file
//! output is not a folder. The writes themselves go through `kshell::io::write_atomic`.

use std::path::{Path, PathBuf};

/// The command's inputs (canonical paths) and whether `--force` was given.
pub struct Guard {
    inputs: Vec<PathBuf>,
    force: bool,
}

/// `path` made absolute with symbolic links resolved, also when the file itself does not exist
/// yet (its folder is resolved and the name appended).
fn resolved(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = path.canonicalize() {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Some(parent.canonicalize().ok()?.join(name))
}

/// Creates and removes a probe file in `dir`: the cheapest honest test that a write will work.
fn writable(dir: &Path) -> Result<(), String> {
    let probe = dir.join(format!(".ks-fit-probe-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .map_err(|e| format!("cannot write in the folder {}: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

impl Guard {
    pub fn new(force: bool) -> Guard {
        Guard {
            inputs: Vec::new(),
            force,
        }
    }

    /// Records an input file (ignored when it cannot be resolved: reading it will say why).
    pub fn input(&mut self, path: &Path) {
        if let Ok(p) = path.canonicalize() {
            self.inputs.push(p);
        }
    }

    fn is_input(&self, p: &Path) -> bool {
        self.inputs.iter().any(|i| i == p)
    }

    /// Checks a file output given by `flag`.
    pub fn file(&self, flag: &str, path: &Path) -> Result<(), String> {
        let shown = path.display();
        if path.is_dir() {
            return Err(format!("{flag} {shown}: is a folder; name a file"));
        }
        let Some(p) = resolved(path) else {
            return Err(format!(
                "{flag} {shown}: the folder it would go in does not exist"
            ));
        };
        if self.is_input(&p) && !self.force {
            return Err(format!(
                "{flag} {shown}: is one of this command's input files and would be overwritten (pass --force to allow it)"
            ));
        }
        if p.file_name().is_some_and(|n| n == "fabric.toml") && p.exists() && !self.force {
            return Err(format!(
                "{flag} {shown}: would overwrite a dataset's fabric.toml (pass --force to allow it)"
            ));
        }
        writable(p.parent().unwrap_or(Path::new("/"))).map_err(|e| format!("{flag} {shown}: {e}"))
    }

    /// Checks a folder output given by `flag`. `own` names a file that only this kind of output
    /// holds (a previous run's folder may be written over); any other non-empty folder, a
    /// dataset folder, or one holding an input, is refused unless `--force`.
    pub fn folder(&self, flag: &str, path: &Path, own: &str) -> Result<(), String> {
        let shown = path.display();
        if path.exists() && !path.is_dir() {
            return Err(format!("{flag} {shown}: is a file, not a folder"));
        }
        if path.is_dir() && !self.force {
            let entries: Vec<PathBuf> = std::fs::read_dir(path)
                .map_err(|e| format!("{flag} {shown}: cannot read the folder: {e}"))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .collect();
            let dir = path
                .canonicalize()
                .map_err(|e| format!("{flag} {shown}: {e}"))?;
            if let Some(i) = self.inputs.iter().find(|i| i.starts_with(&dir)) {
                return Err(format!(
                    "{flag} {shown}: holds this command's input {} (pass --force to write there anyway)",
                    i.display()
                ));
            }
            let holds = |name: &str| {
                entries
                    .iter()
                    .any(|e| e.file_name().is_some_and(|n| n == name))
            };
            if holds("fabric.toml") && own != "fabric.toml" {
                return Err(format!(
                    "{flag} {shown}: is a dataset folder (it holds fabric.toml); pass --force to write there anyway"
                ));
            }
            if !entries.is_empty() && !holds(own) {
                return Err(format!(
                    "{flag} {shown}: the folder is not empty and holds no {own} from an earlier run (pass --force to write there anyway)"
                ));
            }
            if own == "fabric.toml" && holds(own) {
                return Err(format!(
                    "{flag} {shown}: holds a dataset already; pass --force to replace it"
                ));
            }
        }
        // the nearest folder that exists must be writable (the rest is created)
        let mut existing = path.to_path_buf();
        while !existing.is_dir() {
            match existing.parent() {
                Some(p) if !p.as_os_str().is_empty() => existing = p.to_path_buf(),
                _ => {
                    existing = PathBuf::from(".");
                    break;
                }
            }
        }
        writable(&existing).map_err(|e| format!("{flag} {shown}: {e}"))
    }
}
