//! `ks-fit batch`: a small library fitted on this machine (side by side, resumed, with a
//! broken and a failing fabric), the Slurm path run by hand (`--task`, `--collect`), and the
//! same library on a real single-node Slurm cluster started by the test (with
//! `KSHELL_SLURM_TEST=1`, as CI sets it; the test then starts munge and the Slurm daemons
//! itself, so it runs only where asked).

use crate::common::{folder, ks_fit, s};
use std::path::Path;
use std::process::Command;

/// A tiny synthetic dataset (4 points per curve on 4×6 strips) in `dir/name`.
fn dataset(dir: &Path, name: &str) {
    let (rc, _, err) = ks_fit(&[
        "synth",
        "--material",
        "examples/materials/cotton.toml",
        "--out",
        s(&dir.join(name)),
        "--points",
        "4",
        "--mesh",
        "4x6",
    ]);
    assert_eq!(rc, 0, "{err}");
}

/// The library: two fabrics fitted fast (one mesh for every test, degree 1), one whose
/// dataset is missing, one whose fit refuses its options.
fn library(dir: &Path) -> std::path::PathBuf {
    dataset(dir, "a");
    dataset(dir, "b");
    let manifest = dir.join("library.csv");
    std::fs::write(
        &manifest,
        "# two fabrics and two that cannot be fitted\n\
         fabric,dataset,max_degree,mesh_ladder,test_meshes\n\
         cotton-a,a/fabric.toml,1,4x6,ladder\n\
         cotton-b,b/fabric.toml,1,4x6,ladder\n\
         missing,nothere/fabric.toml,,,\n\
         refused,a/fabric.toml,0,4x6,ladder\n",
    )
    .unwrap();
    manifest
}

/// A material file without its timing lines (wall and stage seconds), which are the only
/// lines that may differ between two runs of the same fit.
fn without_times(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.contains("seconds") && !l.starts_with("\""))
        .collect::<Vec<_>>()
        .join("\n")
}

fn summary(out: &Path) -> Vec<csv::StringRecord> {
    let text = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    assert_eq!(
        r.headers().unwrap().iter().collect::<Vec<_>>().join(","),
        "fabric,status,passed,seconds,wall_seconds,objective_evaluations,newton_iterations,worst_curve_error_pct,verdict,warnings,material,report,log,error,worst_shape_error_pct"
    );
    r.records().map(|r| r.unwrap()).collect()
}

#[test]
fn a_library_is_fitted_side_by_side_resumed_and_summarised() {
    let dir = folder("batch");
    let manifest = library(&dir);
    let out = dir.join("out");
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out), "--jobs", "2"]);
    assert_eq!(rc, 3, "a failed fabric makes exit 3: {err}");
    assert!(
        err.contains("4 fabrics: 2 fitted (2 passed, 0 FIT FAILED), 2 failed"),
        "{err}"
    );
    let rows = summary(&out);
    let names: Vec<&str> = rows.iter().map(|r| &r[0]).collect();
    assert_eq!(names, ["cotton-a", "cotton-b", "missing", "refused"]);
    for r in &rows[..2] {
        assert_eq!((&r[1], &r[2]), ("done", "true"), "{r:?}");
        assert!(
            out.join(&r[10]).is_file() && out.join(&r[11]).is_file() && out.join(&r[12]).is_file(),
            "{r:?}"
        );
        assert!(r[8].starts_with("verdict: fit within --max-error"), "{r:?}");
        let worst: f64 = r[7].parse().unwrap();
        assert!(worst > 0.0 && worst < 10.0, "{r:?}");
    }
    assert_eq!(&rows[2][1], "failed");
    assert!(
        rows[2][13].contains("nothere/fabric.toml: cannot read"),
        "{:?}",
        rows[2]
    );
    // the fit's own one-line error is the fabric's
    assert_eq!(&rows[3][1], "failed");
    assert!(rows[3][13].contains("degree"), "{:?}", rows[3]);
    assert!(out.join("refused/log.txt").is_file());
    // the page is well-formed and links each report
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    roxmltree::Document::parse(&html.replace("<!DOCTYPE html>", "")).expect("well-formed page");
    assert!(
        html.contains("href=\"cotton-a/report/index.html\""),
        "{html}"
    );
    // nothing half-written is left
    let work: Vec<_> = std::fs::read_dir(out.join(".work")).unwrap().collect();
    assert!(work.is_empty(), "{work:?}");

    // a rerun skips what is done and retries what failed; a changed curve is fitted again
    let before = std::fs::read_to_string(out.join("cotton-a/material.toml")).unwrap();
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out)]);
    assert_eq!(rc, 3);
    assert!(
        err.contains("cotton-a skipped") && err.contains("cotton-b skipped"),
        "{err}"
    );
    assert!(err.contains("missing FAILED"), "{err}");
    let curve = dir.join("b/weft-1.csv");
    let text = std::fs::read_to_string(&curve).unwrap();
    std::fs::write(
        &curve,
        text.replace("elongation_mm,force_n", "elongation_mm, force_n"),
    )
    .unwrap();
    let (_, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out)]);
    assert!(
        err.contains("cotton-a skipped") && err.contains("cotton-b fitted"),
        "{err}"
    );
    assert_eq!(
        before,
        std::fs::read_to_string(out.join("cotton-a/material.toml")).unwrap()
    );

    // one job or two, the materials are the same to the bit (timings aside)
    let serial = dir.join("serial");
    let (_, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&serial), "--jobs", "1"]);
    for f in ["cotton-a", "cotton-b"] {
        let m = format!("{f}/material.toml");
        assert_eq!(
            without_times(&out.join(&m)),
            without_times(&serial.join(&m)),
            "{err}"
        );
    }

    // one batch per folder: a live batch's lock is respected, a dead one's taken over
    let lock = out.join(".work/batch.lock");
    std::fs::write(&lock, std::process::id().to_string()).unwrap();
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out)]);
    assert_eq!(rc, 2);
    assert!(err.contains("another ks-fit batch (pid"), "{err}");
    std::fs::write(&lock, "4294967295").unwrap();
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out)]);
    assert_eq!(rc, 3, "{err}");
    assert!(err.contains("cotton-a skipped") && !lock.exists(), "{err}");

    // bad flags and manifests are one-line errors with exit code 2
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out), "--jobs", "0"]);
    assert_eq!(rc, 2, "{err}");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "fabric,dataset,colour\nx,y,red\n").unwrap();
    let (rc, _, err) = ks_fit(&["batch", s(&bad), "--out", s(&out)]);
    assert_eq!(rc, 2);
    assert!(err.contains("bad.csv:1: unknown column `colour`"), "{err}");
}

#[test]
fn slurm_tasks_run_their_share_and_collect_builds_the_summary() {
    let dir = folder("batch-tasks");
    let manifest = library(&dir);
    let out = dir.join("out");
    let (rc, stdout, err) = ks_fit(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--slurm",
        "--per-task",
        "3",
    ]);
    assert_eq!(rc, 0, "{err}");
    assert!(stdout.contains("2 array tasks"), "{stdout}");
    let script = std::fs::read_to_string(out.join("batch.sbatch")).unwrap();
    assert!(script.starts_with("#!/bin/bash\n"), "{script}");
    assert!(script.contains("#SBATCH --array=0-1\n"), "{script}");
    assert!(
        script.contains("--per-task 3 --task \"$SLURM_ARRAY_TASK_ID\""),
        "{script}"
    );
    // task 1 is the fourth fabric alone; it writes no summary
    let (rc, _, err) = ks_fit(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--per-task",
        "3",
        "--task",
        "1",
    ]);
    assert_eq!(rc, 3, "{err}");
    assert!(
        err.contains("1 fabrics: 0 fitted") && err.contains("refused failed"),
        "{err}"
    );
    assert!(!out.join("summary.csv").exists() && !out.join("cotton-a").exists());
    let (rc, _, err) = ks_fit(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--per-task",
        "3",
        "--task",
        "2",
    ]);
    assert_eq!(rc, 2);
    assert!(err.contains("make tasks 0 to 1"), "{err}");
    // collect before task 0 has run: three fabrics not run
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out), "--collect"]);
    assert_eq!(rc, 3);
    assert!(err.contains("3 not run"), "{err}");
    let rows = summary(&out);
    assert_eq!(&rows[0][1], "pending");
    assert_eq!(&rows[3][1], "failed");
}

/// Runs `cmd` with the test cluster's configuration; panics with its output on failure.
fn slurm(conf: &Path, cmd: &str, args: &[&str]) -> String {
    let out = Command::new(cmd)
        .args(args)
        .env("SLURM_CONF", conf)
        .output()
        .unwrap_or_else(|e| panic!("{cmd}: {e}"));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{cmd} {args:?}: {text}");
    text
}

/// Polls `check` every half second for up to `seconds`.
fn wait_for(seconds: u64, what: &str, mut check: impl FnMut() -> bool) {
    for _ in 0..2 * seconds {
        if check() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(500));
    }
    panic!("timed out waiting for {what}");
}

/// A single-node Slurm cluster in `dir` (munge, slurmctld and slurmd started here, as root);
/// its configuration file.
fn start_cluster(dir: &Path) -> std::path::PathBuf {
    let host = String::from_utf8(Command::new("hostname").arg("-s").output().unwrap().stdout)
        .unwrap()
        .trim()
        .to_string();
    let works = |c: &str| {
        Command::new("sh")
            .args(["-c", c])
            .status()
            .is_ok_and(|s| s.success())
    };
    if !works("munge -n | unmunge >/dev/null 2>&1") {
        assert!(
            works("mkdir -p /run/munge && chown munge:munge /run/munge && munged --force"),
            "cannot start munged"
        );
        wait_for(10, "munge", || works("munge -n | unmunge >/dev/null 2>&1"));
    }
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let port = 20000 + std::process::id() % 20000;
    let d = dir.display();
    let conf = dir.join("slurm.conf");
    std::fs::create_dir_all(dir.join("state")).unwrap();
    std::fs::create_dir_all(dir.join("spool")).unwrap();
    std::fs::write(
        &conf,
        format!(
            "ClusterName=kshelltest\nSlurmctldHost={host}(127.0.0.1)\nSlurmUser=root\nSlurmdUser=root\n\
             AuthType=auth/munge\nStateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/slurmctld.log\nSlurmdLogFile={d}/slurmd.log\n\
             SlurmctldPort={port}\nSlurmdPort={}\nProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\nJobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\nSchedulerType=sched/builtin\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\nReturnToService=2\n\
             MpiDefault=none\nNodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=test Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            port + 1
        ),
    )
    .unwrap();
    slurm(&conf, "slurmctld", &["-f", s(&conf)]);
    slurm(&conf, "slurmd", &["-f", s(&conf)]);
    wait_for(60, "an idle Slurm node", || {
        Command::new("sinfo")
            .args(["-h", "-o", "%t"])
            .env("SLURM_CONF", &conf)
            .output()
            .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
    });
    conf
}

#[test]
fn a_library_runs_as_a_job_array_on_a_real_slurm_cluster() {
    if std::env::var("KSHELL_SLURM_TEST").as_deref() != Ok("1") {
        eprintln!("skipped: set KSHELL_SLURM_TEST=1 to start a single-node Slurm cluster (as root, with slurm-wlm and munge installed)");
        return;
    }
    let dir = folder("batch-slurm");
    let manifest = library(&dir);
    let out = dir.join("out");
    let conf = start_cluster(&dir.join("cluster"));
    let (rc, _, err) = ks_fit(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--slurm",
        "--per-task",
        "2",
    ]);
    assert_eq!(rc, 0, "{err}");
    let id = slurm(
        &conf,
        "sbatch",
        &["--parsable", s(&out.join("batch.sbatch"))],
    );
    let id = id.trim().split(';').next().unwrap().to_string();
    wait_for(600, "the job array", || {
        Command::new("squeue")
            .args(["-h", "-j", &id])
            .env("SLURM_CONF", &conf)
            .output()
            .is_ok_and(|o| o.status.success() && o.stdout.is_empty())
    });
    let _ = Command::new("scontrol")
        .arg("shutdown")
        .env("SLURM_CONF", &conf)
        .status();
    for t in 0..2 {
        let log = std::fs::read_to_string(out.join(format!("slurm/task-{t}.out")))
            .unwrap_or_else(|e| panic!("task {t}'s output: {e}"));
        assert!(log.contains("ks-fit: batch: 2 fabrics"), "task {t}: {log}");
    }
    let (rc, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&out), "--collect"]);
    assert_eq!(rc, 3, "{err}");
    assert!(
        err.contains("4 fabrics: 2 fitted (2 passed, 0 FIT FAILED), 2 failed, 0 not run"),
        "{err}"
    );
    // the scheduler changes nothing in the materials
    let local = dir.join("local");
    let (_, _, err) = ks_fit(&["batch", s(&manifest), "--out", s(&local), "--jobs", "2"]);
    for f in ["cotton-a", "cotton-b"] {
        let m = format!("{f}/material.toml");
        assert_eq!(
            without_times(&out.join(&m)),
            without_times(&local.join(&m)),
            "{err}"
        );
    }
}
