//! `ks-fit batch`: fit a library of fabrics listed in a manifest, on this machine (`--jobs N`
//! fits side by side) or as a Slurm job array (`--slurm` writes the script, `--task I` runs one
//! array task, `--collect` builds the summary).
//!
//! Each fabric is fitted by a child `ks-fit fit` (a crash of one fit cannot take the others
//! down) into `OUT/.work/<fabric>/`, which is renamed to `OUT/<fabric>/` when it ends: the
//! fabric's folder is either absent or whole. It holds `material.toml`, `report/` (shell fits),
//! `log.txt` (everything the fit printed) and `status.toml` (done or failed, the exit code, the
//! error, the seconds, and the fingerprint of its inputs). A rerun skips every fabric whose
//! status is done with the same fingerprint, and runs failed and changed ones again.
//! `OUT/summary.csv` and `OUT/index.html` are rewritten (atomically) as fabrics finish, at most
//! every few seconds (`progress`), and when the batch ends.
//!
//! With `--jobs N` above 1 each fit runs on one thread (`RAYON_NUM_THREADS=1`); a fit's
//! material is the same to the bit whatever its thread count, so the batch's materials do not
//! depend on the job count or the scheduler.

pub mod manifest;
pub mod progress;
pub mod summary;

use manifest::{inputs_hash, read_manifest, Row};
use progress::{time_left, Pace};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;
use summary::{read_status, summary_csv, summary_html, Entry, Status};

/// `ks-fit batch` options.
#[derive(clap::Args)]
pub struct BatchArgs {
    /// The manifest: CSV with the columns `fabric` (the fabric's folder name under --out) and
    /// `dataset` (its fabric.toml, relative to the manifest's folder), then any of the fit
    /// options model, max_degree, degree, mesh_ladder, method, protocol, toe, repeat,
    /// max_misalign, nodes, max_error, strategy, bending, mesh_check, grading, test_meshes,
    /// yarn_rule, shear_coupling, objective, joint (an empty cell keeps the default). Lines starting with # are comments.
    manifest: PathBuf,
    /// Output folder: one folder per fabric, summary.csv and index.html.
    #[arg(long)]
    out: PathBuf,
    /// Fits run side by side on this machine, each on one thread then (for throughput).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Write OUT/batch.sbatch, a Slurm job-array script (one array task per --per-task
    /// fabrics, each running `ks-fit batch … --task I`), and print how to submit it.
    #[arg(long, conflicts_with_all = ["task", "collect"])]
    slurm: bool,
    /// Fabrics per array task (with --slurm and --task).
    #[arg(long, default_value_t = 1)]
    per_task: usize,
    /// Run array task I: the fabrics I·K to I·K + K − 1 in manifest order (K = --per-task),
    /// one after another. The summary is left to --collect.
    #[arg(long, conflicts_with = "collect")]
    task: Option<usize>,
    /// Build summary.csv and index.html from the fabrics' folders, running nothing.
    #[arg(long)]
    collect: bool,
}

/// Most fits side by side.
const MAX_JOBS: usize = 256;

/// Runs `ks-fit batch`: `Ok(true)` when every fabric of the manifest is fitted and passed.
pub fn cmd_batch(a: &BatchArgs) -> Result<bool, String> {
    let rows = read_manifest(&a.manifest)?;
    if !(1..=MAX_JOBS).contains(&a.jobs) {
        return Err(format!("--jobs must be in [1, {MAX_JOBS}], got {}", a.jobs));
    }
    if a.per_task == 0 {
        return Err("--per-task must be at least 1".into());
    }
    std::fs::create_dir_all(&a.out)
        .map_err(|e| format!("--out {}: cannot create the folder: {e}", a.out.display()))?;
    if a.slurm {
        return write_slurm(a, rows.len()).map(|()| true);
    }
    let chosen: Vec<usize> = match a.task {
        Some(t) => {
            let tasks = rows.len().div_ceil(a.per_task);
            if t >= tasks {
                return Err(format!(
                    "--task {t}: the manifest's {} fabrics at --per-task {} make tasks 0 to {}",
                    rows.len(),
                    a.per_task,
                    tasks - 1
                ));
            }
            (t * a.per_task..((t + 1) * a.per_task).min(rows.len())).collect()
        }
        None if a.collect => Vec::new(),
        None => (0..rows.len()).collect(),
    };
    let exe = std::env::current_exe().map_err(|e| format!("cannot find ks-fit itself: {e}"))?;
    let summary = a.task.is_none();
    // one local batch per folder (array tasks share it by design, on disjoint fabrics)
    let _lock = match a.task {
        None => Some(Lock::take(&a.out)?),
        Some(_) => None,
    };
    let mut board = Board::new(&rows, &a.out);
    if summary {
        board.write(&a.out, &a.manifest)?;
    }
    run_all(&exe, &rows, &chosen, a, &mut board, summary)?;
    if summary {
        board.write(&a.out, &a.manifest)?;
    }
    Ok(board.report(&chosen, a.task.is_some()))
}

/// `DIR/.work/batch.lock`, holding the pid of the batch that runs in DIR; removed on drop. A
/// lock whose process is gone (a batch killed) is taken over.
struct Lock(PathBuf);

impl Lock {
    fn take(out: &Path) -> Result<Lock, String> {
        use std::io::Write;
        let dir = out.join(".work");
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("{}: cannot create: {e}", dir.display()))?;
        let path = dir.join("batch.lock");
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    let _ = write!(f, "{}", std::process::id());
                    return Ok(Lock(path));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let pid = std::fs::read_to_string(&path).unwrap_or_default();
                    let alive = pid.trim().parse::<u32>().is_ok_and(|p| {
                        p != std::process::id() && Path::new(&format!("/proc/{p}")).exists()
                    });
                    if alive {
                        return Err(format!(
                            "another ks-fit batch (pid {}) is running in {}; wait for it, or remove {} if it is not",
                            pid.trim(),
                            out.display(),
                            path.display()
                        ));
                    }
                    let _ = std::fs::remove_file(&path);
                }
                Err(e) => return Err(format!("{}: cannot create: {e}", path.display())),
            }
        }
        Err(format!("{}: cannot take the lock", path.display()))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// What the batch knows of every fabric.
struct Board<'a> {
    rows: &'a [Row],
    status: Vec<Option<Status>>,
    running: Vec<bool>,
}

impl<'a> Board<'a> {
    fn new(rows: &'a [Row], out: &Path) -> Self {
        Board {
            rows,
            status: rows
                .iter()
                .map(|r| read_status(&out.join(&r.fabric)))
                .collect(),
            running: vec![false; rows.len()],
        }
    }

    fn write(&self, out: &Path, manifest: &Path) -> Result<(), String> {
        let entries: Vec<Entry> = self
            .rows
            .iter()
            .enumerate()
            .map(|(i, row)| Entry {
                row,
                status: self.status[i].clone(),
                running: self.running[i],
            })
            .collect();
        let title = format!("ks-fit batch: {}", manifest.display());
        for (name, text) in [
            ("summary.csv", summary_csv(out, &entries)),
            ("index.html", summary_html(out, &entries, &title)),
        ] {
            let path = out.join(name);
            kshell::io::write_atomic(&path, text)
                .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
        }
        Ok(())
    }

    /// The closing lines on stderr; true when every fabric looked at is done and passed.
    fn report(&self, chosen: &[usize], task: bool) -> bool {
        let looked: Vec<usize> = if task {
            chosen.to_vec()
        } else {
            (0..self.rows.len()).collect()
        };
        let count = |f: &dyn Fn(&Status) -> bool| {
            looked
                .iter()
                .filter(|&&i| self.status[i].as_ref().is_some_and(f))
                .count()
        };
        let done = count(&|s| s.is_done());
        let passed = count(&|s| s.is_done() && s.passed);
        let failed = count(&|s| !s.is_done());
        let pending = looked.len() - done - failed;
        eprintln!(
            "ks-fit: batch: {} fabrics: {done} fitted ({passed} passed, {} FIT FAILED), {failed} failed, {pending} not run",
            looked.len(),
            done - passed,
        );
        for &i in &looked {
            if let Some(s) = self.status[i].as_ref().filter(|s| !s.is_done()) {
                eprintln!("ks-fit: batch: {} failed: {}", self.rows[i].fabric, s.error);
            }
        }
        passed == looked.len()
    }
}

/// Runs the chosen fabrics, `a.jobs` at a time, updating the board as each ends (and the
/// summary files when `summary`, at the pace of [`Pace`]: the caller writes them at the end).
fn run_all(
    exe: &Path,
    rows: &[Row],
    chosen: &[usize],
    a: &BatchArgs,
    board: &mut Board,
    summary: bool,
) -> Result<(), String> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    enum Msg {
        Started(usize),
        /// the row, its status, whether it is skipped (done with unchanged inputs), its wall
        /// time in seconds
        Finished(usize, Status, bool, f64),
    }
    let next = AtomicUsize::new(0);
    let (tx, rx) = std::sync::mpsc::channel();
    let jobs = a.jobs.min(chosen.len().max(1));
    // fits side by side each take one thread; a lone fit keeps them all
    let single = jobs > 1;
    let start = Instant::now();
    std::thread::scope(|s| -> Result<(), String> {
        for _ in 0..jobs {
            let tx = tx.clone();
            let next = &next;
            s.spawn(move || loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&i) = chosen.get(k) else { break };
                let _ = tx.send(Msg::Started(i));
                let t0 = Instant::now();
                let (status, skipped) = run_fabric(exe, &rows[i], &a.out, single);
                let wall = t0.elapsed().as_secs_f64();
                let _ = tx.send(Msg::Finished(i, status, skipped, wall));
            });
        }
        drop(tx);
        let (mut finished, mut failed) = (0usize, 0usize);
        // wall times of the fabrics run (not skipped), for the estimate of the time left
        let mut walls: Vec<f64> = Vec::new();
        let mut pace = Pace::new(Instant::now());
        for msg in rx {
            match msg {
                Msg::Started(i) => board.running[i] = true,
                Msg::Finished(i, status, skipped, wall) => {
                    board.running[i] = false;
                    finished += 1;
                    if !skipped {
                        walls.push(wall);
                    }
                    let what = match (skipped, status.is_done(), status.passed) {
                        (true, ..) => "skipped (done before, inputs unchanged)".to_string(),
                        (false, true, true) => format!("fitted in {:.1} s", status.seconds),
                        (false, true, false) => {
                            format!(
                                "fitted in {:.1} s, FIT FAILED (see its log)",
                                status.seconds
                            )
                        }
                        (false, false, _) => format!("FAILED: {}", status.error),
                    };
                    failed += usize::from(!status.is_done());
                    board.status[i] = Some(status);
                    let pace = start.elapsed().as_secs_f64() / finished as f64;
                    let eta = time_left(&walls, chosen.len() - finished, jobs, pace);
                    eprintln!(
                        "ks-fit: batch: {} {what}; {finished} of {} done ({failed} failed) after {:.0} s{eta}",
                        rows[i].fabric,
                        chosen.len(),
                        start.elapsed().as_secs_f64()
                    );
                }
            }
            if summary && pace.due(Instant::now()) {
                let t0 = Instant::now();
                board.write(&a.out, &a.manifest)?;
                pace.wrote(Instant::now(), t0.elapsed());
            }
        }
        Ok(())
    })
}

/// Fits one fabric unless it is done with the same inputs; returns its status and whether it
/// was skipped.
fn run_fabric(exe: &Path, row: &Row, out: &Path, single_thread: bool) -> (Status, bool) {
    let dir = out.join(&row.fabric);
    let failed = |hash: String, error: String| Status {
        status: "failed".into(),
        passed: false,
        hash,
        exit_code: None,
        seconds: 0.0,
        error,
        warnings: 0,
        first_warning: String::new(),
    };
    let hash = match inputs_hash(row) {
        Ok(h) => h,
        Err(e) => {
            let s = failed(String::new(), e);
            return (install(row, out, s.clone(), None).unwrap_or(s), false);
        }
    };
    if let Some(s) = read_status(&dir) {
        if s.is_done() && s.hash == hash && dir.join("material.toml").is_file() {
            return (s, true);
        }
    }
    let work = out.join(".work").join(&row.fabric);
    let _ = std::fs::remove_dir_all(&work);
    if let Err(e) = std::fs::create_dir_all(&work) {
        return (
            failed(hash, format!("{}: cannot create: {e}", work.display())),
            false,
        );
    }
    let t0 = Instant::now();
    let result = fit_child(exe, row, &work, single_thread);
    let seconds = t0.elapsed().as_secs_f64();
    let log = std::fs::read_to_string(work.join("log.txt")).unwrap_or_default();
    let warnings: Vec<&str> = log
        .lines()
        .filter(|l| l.to_ascii_lowercase().contains("warning"))
        .collect();
    let error_line = log
        .lines()
        .rev()
        .find_map(|l| l.strip_prefix("ks-fit: error: "))
        .map(str::to_string);
    let mut status = Status {
        status: "done".into(),
        passed: false,
        hash,
        exit_code: None,
        seconds,
        error: String::new(),
        warnings: warnings.len(),
        first_warning: warnings.first().map(|w| w.to_string()).unwrap_or_default(),
    };
    match result {
        Ok(code) => {
            status.exit_code = code;
            match code {
                Some(0) | Some(3) if work.join("material.toml").is_file() => {
                    status.passed = code == Some(0);
                }
                Some(0) | Some(3) => {
                    status.status = "failed".into();
                    status.error = "the fit wrote no material".into();
                }
                _ => {
                    status.status = "failed".into();
                    status.error = error_line.unwrap_or_else(|| match code {
                        Some(c) => format!("the fit ended with exit code {c} (see log.txt)"),
                        None => "the fit was killed by a signal (see log.txt)".into(),
                    });
                }
            }
        }
        Err(e) => {
            status.status = "failed".into();
            status.error = e;
        }
    }
    let installed = install(row, out, status.clone(), Some(&work));
    match installed {
        Ok(s) => (s, false),
        Err(e) => (failed(status.hash, e), false),
    }
}

/// `ks-fit fit` on the row, into `work`, its output in `work/log.txt`; the exit code.
fn fit_child(
    exe: &Path,
    row: &Row,
    work: &Path,
    single_thread: bool,
) -> Result<Option<i32>, String> {
    let log_path = work.join("log.txt");
    let log = std::fs::File::create(&log_path)
        .map_err(|e| format!("{}: cannot create: {e}", log_path.display()))?;
    let err = log
        .try_clone()
        .map_err(|e| format!("{}: {e}", log_path.display()))?;
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| format!("{}: {e}", p.display()));
    let folder = match row.folder.as_os_str().is_empty() {
        true => absolute(Path::new("."))?,
        false => absolute(&row.folder)?,
    };
    let mut cmd = Command::new(exe);
    cmd.current_dir(folder)
        .arg("fit")
        .arg(&row.given)
        .arg("-o")
        .arg(absolute(&work.join("material.toml"))?);
    if row.model() == crate::flags::DEFAULT_MODEL {
        cmd.arg("--report").arg(absolute(&work.join("report"))?);
    }
    cmd.args(row.fit_args())
        .stdin(Stdio::null())
        .stdout(log)
        .stderr(err);
    if single_thread {
        cmd.env("RAYON_NUM_THREADS", "1");
    }
    let status = cmd
        .status()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    Ok(status.code())
}

/// Writes the status into the fabric's new folder (`work`, or a fresh one when there is no
/// work folder) and moves that folder into place, replacing the old one.
fn install(row: &Row, out: &Path, status: Status, work: Option<&Path>) -> Result<Status, String> {
    let fresh;
    let work = match work {
        Some(w) => w,
        None => {
            fresh = out.join(".work").join(&row.fabric);
            let _ = std::fs::remove_dir_all(&fresh);
            std::fs::create_dir_all(&fresh)
                .map_err(|e| format!("{}: cannot create: {e}", fresh.display()))?;
            &fresh
        }
    };
    let path = work.join("status.toml");
    kshell::io::write_atomic(&path, status.to_toml(row))
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    let dir = out.join(&row.fabric);
    let old = out.join(".work").join(format!("{}.old", row.fabric));
    let _ = std::fs::remove_dir_all(&old);
    if dir.exists() {
        std::fs::rename(&dir, &old)
            .map_err(|e| format!("{}: cannot move aside: {e}", dir.display()))?;
    }
    std::fs::rename(work, &dir)
        .map_err(|e| format!("{}: cannot move into place: {e}", dir.display()))?;
    let _ = std::fs::remove_dir_all(&old);
    Ok(status)
}

/// A path for a shell script: absolute, single-quoted.
fn quoted(p: &Path) -> Result<String, String> {
    let abs: PathBuf = std::path::absolute(p).map_err(|e| format!("{}: {e}", p.display()))?;
    let s = abs
        .to_str()
        .ok_or_else(|| format!("{}: not valid UTF-8", abs.display()))?;
    Ok(format!("'{}'", s.replace('\'', "'\\''")))
}

/// Writes `OUT/batch.sbatch` and says how to submit and collect.
fn write_slurm(a: &BatchArgs, fabrics: usize) -> Result<(), String> {
    let tasks = fabrics.div_ceil(a.per_task);
    let exe = std::env::current_exe().map_err(|e| format!("cannot find ks-fit itself: {e}"))?;
    let (exe, manifest, out) = (quoted(&exe)?, quoted(&a.manifest)?, quoted(&a.out)?);
    let logs = a.out.join("slurm");
    std::fs::create_dir_all(&logs)
        .map_err(|e| format!("{}: cannot create: {e}", logs.display()))?;
    let script = format!(
        "#!/bin/bash\n\
         # written by ks-fit batch --slurm: {fabrics} fabrics, {k} per array task\n\
         #SBATCH --job-name=ks-fit-batch\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --ntasks=1\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --output={logs}/task-%a.out\n\
         set -eu\n\
         export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\"\n\
         exec {exe} batch {manifest} --out {out} --per-task {k} --task \"$SLURM_ARRAY_TASK_ID\"\n",
        k = a.per_task,
        last = tasks - 1,
        logs = std::path::absolute(&logs)
            .map_err(|e| e.to_string())?
            .display(),
    );
    let path = a.out.join("batch.sbatch");
    kshell::io::write_atomic(&path, script)
        .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    println!("wrote {} ({tasks} array tasks)", path.display());
    println!("submit:  sbatch {}", path.display());
    println!(
        "then:    ks-fit batch {} --out {} --collect",
        a.manifest.display(),
        a.out.display()
    );
    Ok(())
}
