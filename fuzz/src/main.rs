//! rae-fuzz: seeded mutation fuzzing of rae's readers, weights loader and command line, on a
//! stable toolchain. `rae-fuzz SECONDS` replays the kept regressions, then runs every target
//! in turn until the time is up, in a worker process it restarts after a crash, and prints
//! cases per target and findings on its last line. A finding is a panic, an abort, a case past
//! the time limit, an allocation past the memory limit, or an error that names no file; each
//! is written to the crashes folder, to be kept under `fuzz/regressions/TARGET/` once fixed.

mod limits;
mod mutate;
mod targets;

use std::collections::{BTreeMap, HashMap, HashSet};
use std::hash::{DefaultHasher, Hash, Hasher};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Parser;
use mutate::{Rng, mutate};
use targets::{Outcome, Target};

#[global_allocator]
static ALLOCATOR: limits::Counting = limits::Counting;

#[derive(Parser)]
#[command(name = "rae-fuzz", about = "Seeded mutation fuzzing of rae's readers, weights loader and command line")]
struct Cli {
    /// Seconds to fuzz in all (the regressions are replayed first).
    #[arg(default_value_t = 60)]
    seconds: u64,
    /// Seed of the first worker (each restart takes the next).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Only these targets (weights, golden, exr, multilayer, image, args).
    #[arg(long, value_delimiter = ',')]
    targets: Vec<String>,
    /// A case running longer than this is a hang.
    #[arg(long, default_value_t = 10)]
    case_limit_s: u64,
    /// A worker whose live heap passes this many MiB has allocated without bound (above what
    /// the largest frame rae reads may take: rae_core::io::MAX_SAMPLES).
    #[arg(long, default_value_t = 5120)]
    memory_limit_mib: usize,
    /// Repository root (the sample and fixtures seed the corpus).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/.."))]
    root: PathBuf,
    /// Where findings are written.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/crashes"))]
    crashes: PathBuf,
    /// Replay these case files (their folder names their target) and stop.
    #[arg(long, num_args = 1.., conflicts_with = "worker")]
    replay: Vec<PathBuf>,
    /// Run as the worker, in this scratch folder (internal).
    #[arg(long, hide = true)]
    worker: Option<PathBuf>,
}

/// The message and place of the last panic, kept by the panic hook.
static PANIC: Mutex<Option<String>> = Mutex::new(None);

fn quiet_panics() {
    std::panic::set_hook(Box::new(|info| {
        let at = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
        let message =
            info.payload().downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| info.payload().downcast_ref::<String>().cloned());
        *PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("panic{at}: {}", message.unwrap_or_default()));
    }));
}

/// Runs a case, a panic caught: `None` when it passed, else what went wrong.
fn try_case(target: &Target, case: &[u8], watchdog: &limits::Watchdog) -> (Option<String>, Option<String>) {
    watchdog.running(true);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| target.run(case)));
    watchdog.running(false);
    match result {
        Ok(Outcome::Accepted) => (None, None),
        Ok(Outcome::Refused(message)) => (None, Some(message)),
        Ok(Outcome::Finding(message)) => (Some(message), None),
        Err(_) => (Some(PANIC.lock().unwrap_or_else(|e| e.into_inner()).take().unwrap_or_else(|| "panic".into())), None),
    }
}

fn save_finding(crashes: &Path, target: &str, case: &[u8], why: &str) -> Result<PathBuf> {
    std::fs::create_dir_all(crashes).with_context(|| format!("creating {}", crashes.display()))?;
    let mut h = DefaultHasher::new();
    case.hash(&mut h);
    let path = crashes.join(format!("{target}-{:016x}.case", h.finish()));
    std::fs::write(&path, case).with_context(|| format!("writing {}", path.display()))?;
    std::fs::write(path.with_extension("txt"), format!("{why}\n")).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

fn select(all: Vec<Target>, names: &[String]) -> Result<Vec<Target>> {
    for n in names {
        if !all.iter().any(|t| t.name == n) {
            bail!("unknown target `{n}` (known: {})", all.iter().map(|t| t.name).collect::<Vec<_>>().join(", "));
        }
    }
    Ok(all.into_iter().filter(|t| names.is_empty() || names.iter().any(|n| n == t.name)).collect())
}

/// The worker: fuzzes the targets in turn, half a second each, until `seconds` are up,
/// printing `count TARGET N` after each turn and `finding TARGET FILE WHY` for each finding.
fn worker(cli: &Cli, scratch: &Path) -> Result<()> {
    let mut targets = select(targets::all(&cli.root, scratch)?, &cli.targets)?;
    let current = scratch.join("current.case");
    let watchdog = limits::Watchdog::start(Duration::from_secs(cli.case_limit_s));
    limits::set_memory_limit(cli.memory_limit_mib << 20);
    quiet_panics();
    let mut rng = Rng::new(cli.seed);
    let deadline = Instant::now() + Duration::from_secs(cli.seconds);
    let mut counts = vec![0u64; targets.len()];
    let mut kinds: Vec<HashSet<String>> = vec![HashSet::new(); targets.len()];
    let mut per_finding: HashMap<String, usize> = HashMap::new();
    while Instant::now() < deadline {
        for (t, target) in targets.iter_mut().enumerate() {
            let turn = Instant::now() + Duration::from_millis(500);
            std::fs::write(scratch.join("current.target"), target.name)?;
            while Instant::now() < turn.min(deadline) {
                let base = &target.corpus[rng.below(target.corpus.len())];
                let other = &target.corpus[rng.below(target.corpus.len())];
                let words: Vec<&[u8]> = target.words.iter().map(Vec::as_slice).collect();
                let case = mutate(&mut rng, base, other, &words);
                // On disk before it runs: if it kills the process, the supervisor files it.
                std::fs::write(&current, &case)?;
                let (finding, refusal) = try_case(target, &case, &watchdog);
                counts[t] += 1;
                if let Some(why) = finding {
                    let n = per_finding.entry(Target::error_kind(&why)).or_default();
                    *n += 1;
                    if *n <= 3 {
                        let path = save_finding(&cli.crashes, target.name, &case, &why)?;
                        println!("finding {} {} {}", target.name, path.display(), why.replace('\n', " "));
                    }
                } else if let Some(message) = refusal
                    && kinds[t].insert(Target::error_kind(&message))
                    && target.corpus.len() < 256
                {
                    // A new kind of refusal: this case got somewhere new; mutate it further.
                    target.corpus.push(case);
                }
            }
            println!("count {} {}", target.name, counts[t]);
        }
    }
    Ok(())
}

/// Replays case files, each through the target its folder names; fails on any finding.
fn replay(cli: &Cli, files: &[PathBuf]) -> Result<()> {
    let scratch = tempdir("replay")?;
    let targets = targets::all(&cli.root, &scratch)?;
    let watchdog = limits::Watchdog::start(Duration::from_secs(cli.case_limit_s));
    limits::set_memory_limit(cli.memory_limit_mib << 20);
    quiet_panics();
    let mut bad = 0;
    for f in files {
        let name = f.parent().and_then(|p| p.file_name()).map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
        let target = targets.iter().find(|t| t.name == name).with_context(|| format!("{}: its folder names no target", f.display()))?;
        let case = std::fs::read(f).with_context(|| format!("reading {}", f.display()))?;
        match try_case(target, &case, &watchdog) {
            (Some(why), _) => {
                println!("{}: {why}", f.display());
                bad += 1;
            }
            (None, refusal) => println!("{}: {}", f.display(), refusal.as_deref().unwrap_or("read")),
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    if bad > 0 {
        bail!("{bad} of {} regression cases fail", files.len());
    }
    Ok(())
}

fn tempdir(what: &str) -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("rae-fuzz-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(dir)
}

/// Every kept regression case, `fuzz/regressions/TARGET/*`.
fn regressions(root: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let dir = root.join("fuzz/regressions");
    for t in std::fs::read_dir(&dir).with_context(|| format!("reading {}", dir.display()))? {
        let t = t?.path();
        if t.is_dir() {
            for f in std::fs::read_dir(&t)? {
                let f = f?.path();
                if f.is_file() && f.extension().is_none_or(|e| e != "txt") {
                    files.push(f);
                }
            }
        }
    }
    files.sort();
    Ok(files)
}

/// The supervisor: replays the regressions, then runs workers until the time is up.
fn supervise(cli: &Cli) -> Result<()> {
    let exe = std::env::current_exe()?;
    let kept = regressions(&cli.root)?;
    if !kept.is_empty() {
        let status = Command::new(&exe).arg("--root").arg(&cli.root).arg("--replay").args(&kept).stdout(Stdio::null()).status()?;
        if !status.success() {
            bail!("a kept regression case fails again: rae-fuzz --replay fuzz/regressions/*/* says which");
        }
        println!("{} regression cases replayed: none fails", kept.len());
    }
    let start = Instant::now();
    let deadline = start + Duration::from_secs(cli.seconds);
    let mut totals: BTreeMap<String, u64> = BTreeMap::new();
    let mut findings: BTreeMap<String, u64> = BTreeMap::new();
    let mut seed = cli.seed;
    while Instant::now() + Duration::from_secs(1) < deadline {
        let scratch = tempdir(&format!("worker{seed}"))?;
        let left = deadline.saturating_duration_since(Instant::now()).as_secs().max(1);
        let mut cmd = Command::new(&exe);
        cmd.arg(left.to_string()).arg("--seed").arg(seed.to_string()).arg("--worker").arg(&scratch);
        cmd.arg("--root").arg(&cli.root).arg("--crashes").arg(&cli.crashes);
        cmd.arg("--case-limit-s").arg(cli.case_limit_s.to_string()).arg("--memory-limit-mib").arg(cli.memory_limit_mib.to_string());
        if !cli.targets.is_empty() {
            cmd.arg("--targets").arg(cli.targets.join(","));
        }
        let mut child = cmd.stdout(Stdio::piped()).spawn().context("starting a worker")?;
        let mut counts: BTreeMap<String, u64> = BTreeMap::new();
        for line in BufReader::new(child.stdout.take().context("worker stdout")?).lines() {
            let line = line?;
            let mut parts = line.splitn(3, ' ');
            match (parts.next(), parts.next(), parts.next()) {
                (Some("count"), Some(t), Some(n)) => {
                    counts.insert(t.to_string(), n.parse().unwrap_or(0));
                }
                (Some("finding"), Some(t), Some(rest)) => {
                    *findings.entry(t.to_string()).or_default() += 1;
                    println!("finding in {t}: {rest}");
                }
                _ => println!("{line}"),
            }
        }
        let status = child.wait()?;
        for (t, n) in counts {
            *totals.entry(t).or_default() += n;
        }
        if !status.success() {
            // The worker died on a case: abort (memory), hang, or a crash outside the catch.
            let target = std::fs::read_to_string(scratch.join("current.target")).unwrap_or_else(|_| "unknown".into());
            let case = std::fs::read(scratch.join("current.case")).unwrap_or_default();
            let why = match status.code() {
                Some(limits::HANG_EXIT) => format!("a case ran past {} s (hang)", cli.case_limit_s),
                Some(c) => format!("the worker exited with status {c}"),
                None => "the worker was killed by a signal (an abort: an allocation past the memory limit, or a crash)".into(),
            };
            let path = save_finding(&cli.crashes, &target, &case, &why)?;
            println!("finding in {target}: {} {why}", path.display());
            *findings.entry(target).or_default() += 1;
            seed += 1;
        }
        let _ = std::fs::remove_dir_all(&scratch);
        if status.success() {
            break;
        }
    }
    let total: u64 = findings.values().sum();
    println!("{:>12} {:>10} {:>9}", "target", "cases", "findings");
    for (t, n) in &totals {
        println!("{t:>12} {n:>10} {:>9}", findings.get(t).copied().unwrap_or(0));
    }
    let cases: Vec<String> = totals.iter().map(|(t, n)| format!("{t} {n}")).collect();
    if total > 0 {
        println!("findings are in {}: fix each, then keep it under fuzz/regressions/TARGET/", cli.crashes.display());
    }
    println!("fuzz: {:.0} s, cases per target: {}; findings: {total}", start.elapsed().as_secs_f64(), cases.join(", "));
    if total > 0 {
        // The summary is the last line; the status says it failed.
        std::process::exit(1);
    }
    Ok(())
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    if let Some(scratch) = &cli.worker {
        worker(&cli, scratch)
    } else if !cli.replay.is_empty() {
        replay(&cli, &cli.replay)
    } else {
        supervise(&cli)
    }
}
