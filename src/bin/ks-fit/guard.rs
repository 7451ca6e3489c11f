//! Output paths checked before any work starts: an output never replaces one of the command's
//! inputs or a dataset folder (unless `--force`), its folder exists and is writable, a file
//! output is a regular file or a new path (never a device, FIFO, socket or folder), and a
//! folder output is empty, new, or an earlier output of the same kind (its marker file says
//! so). Each checked output is locked (`crate::lock`) until the guard is dropped. The writes
//! themselves go through `kshell::io::write_atomic`.

use crate::lock::OutputLock;
use std::path::{Path, PathBuf};

/// The command's inputs (canonical paths), whether `--force` was given, and the locks of the
/// outputs checked so far.
pub struct Guard {
    inputs: Vec<PathBuf>,
    force: bool,
    locks: Vec<OutputLock>,
}

/// The file that marks a folder as an earlier output of the same kind, and the test its text
/// must pass: a file of that name that fails it (written by someone else) marks nothing.
pub struct Marker {
    pub file: &'static str,
    pub ours: fn(&str) -> bool,
}

/// Largest marker file read, bytes (a report's summary.txt is a few kilobytes).
const MAX_MARKER_BYTES: u64 = 16 << 20;

impl Marker {
    /// Whether the folder `dir` holds this marker, written by ks-fit.
    fn marks(&self, dir: &Path) -> bool {
        kshell::io::read_text(&dir.join(self.file), MAX_MARKER_BYTES)
            .is_ok_and(|text| (self.ours)(&text))
    }
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
            locks: Vec::new(),
        }
    }

    /// Records the dataset's files as inputs (its TOML, curves and shape OBJs).
    pub fn dataset(&mut self, data: &kshell::dataset::FabricDataset) {
        for f in data.files() {
            self.input(&f);
        }
    }

    /// Locks `path` for this command (once, however many flags name it).
    fn lock(&mut self, flag: &str, path: &Path) -> Result<(), String> {
        let held =
            crate::lock::lock_path(path).is_some_and(|p| self.locks.iter().any(|l| l.path() == p));
        if !held {
            self.locks.push(crate::lock::take(flag, path)?);
        }
        Ok(())
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

    /// Checks a file output given by `flag` and locks it.
    pub fn file(&mut self, flag: &str, path: &Path) -> Result<(), String> {
        let shown = path.display();
        if path.is_dir() {
            return Err(format!("{flag} {shown}: is a folder; name a file"));
        }
        if let Some(kind) = kshell::io::special_kind(path) {
            return Err(format!(
                "{flag} {shown}: is {kind}, not a regular file; outputs are written only to regular files or new paths"
            ));
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
        writable(p.parent().unwrap_or(Path::new("/")))
            .map_err(|e| format!("{flag} {shown}: {e}"))?;
        self.lock(flag, path)
    }

    /// Checks a folder output given by `flag` and locks it. `own` marks an earlier output of
    /// the same kind (which may be written over); any other non-empty folder, a dataset folder,
    /// or one holding an input, is refused unless `--force`.
    pub fn folder(&mut self, flag: &str, path: &Path, own: &Marker) -> Result<(), String> {
        let shown = path.display();
        if path.exists() && !path.is_dir() {
            let kind = kshell::io::special_kind(path).unwrap_or("a file");
            return Err(format!("{flag} {shown}: is {kind}, not a folder"));
        }
        if path.is_dir() && !self.force {
            self.not_foreign(flag, path, own)?;
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
        writable(&existing).map_err(|e| format!("{flag} {shown}: {e}"))?;
        self.lock(flag, path)
    }

    /// Refuses an existing folder `path` that holds an input, a dataset, or files that are no
    /// earlier output marked by `own`.
    fn not_foreign(&self, flag: &str, path: &Path, own: &Marker) -> Result<(), String> {
        let shown = path.display();
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
        let own_name = own.file;
        if holds("fabric.toml") && own_name != "fabric.toml" {
            return Err(format!(
                "{flag} {shown}: is a dataset folder (it holds fabric.toml); pass --force to write there anyway"
            ));
        }
        if own_name == "fabric.toml" && holds(own_name) {
            return Err(format!(
                "{flag} {shown}: holds a dataset already; pass --force to replace it"
            ));
        }
        if !entries.is_empty() && !holds(own_name) {
            return Err(format!(
                "{flag} {shown}: the folder is not empty and holds no {own_name} from an earlier run (pass --force to write there anyway)"
            ));
        }
        if !entries.is_empty() && !own.marks(path) {
            return Err(format!(
                "{flag} {shown}: the folder is not empty and its {own_name} is not from an earlier run of ks-fit (pass --force to write there anyway)"
            ));
        }
        Ok(())
    }
}
