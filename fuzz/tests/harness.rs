//! The harness itself: kept regression cases replay clean, and a worker that dies (here on an
//! allocation past a memory limit of nothing) is a finding that fails the run.

use std::path::Path;
use std::process::Command;

fn fuzz() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rae-fuzz"))
}

#[test]
fn every_kept_regression_case_replays_without_a_finding() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions");
    let mut files = Vec::new();
    for target in std::fs::read_dir(&dir).unwrap() {
        for f in std::fs::read_dir(target.unwrap().path()).unwrap() {
            files.push(f.unwrap().path());
        }
    }
    assert!(!files.is_empty(), "regression cases are kept in {}", dir.display());
    let out = fuzz().arg("--replay").args(&files).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    // Each is refused with an error that names the file it came from.
    assert_eq!(text.lines().count(), files.len(), "{text}");
    assert!(text.lines().all(|l| l.matches(".exr").count() + l.matches(".safetensors").count() + l.matches(".png").count() >= 1), "{text}");
}

#[test]
fn a_worker_killed_by_the_memory_limit_is_a_finding_and_fails_the_run() {
    let crashes = tempfile::tempdir().unwrap();
    let out = fuzz().args(["2", "--targets", "args", "--memory-limit-mib", "0", "--crashes"]).arg(crashes.path()).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{text}");
    let last = text.lines().last().unwrap_or_default();
    assert!(last.starts_with("fuzz: ") && !last.ends_with("findings: 0"), "{last}");
    assert!(std::fs::read_dir(crashes.path()).unwrap().count() > 0, "the case is kept");
}
