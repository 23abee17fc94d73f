//! Installing LinuxCNC's `rs274` once for the tests of both crates (included with `#[path]`
//! by tests/common/mod.rs and toolpaths/tests/common/mod.rs).

/// Makes sure LinuxCNC's `rs274` is installed before `check-gcode` (the shared tool at `tool`)
/// runs: its first use installs the Debian package, and tests running in parallel must not start
/// that install at the same time (apt's lock turns all but one into a set-up failure). The first
/// caller installs under an exclusive file lock; the others wait for it.
pub fn ensure_rs274(tool: &std::path::Path) {
    let installed = || {
        std::process::Command::new("sh")
            .args(["-c", "command -v rs274"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if installed() {
        return;
    }
    let lock_path = std::env::temp_dir().join("grainline-rs274-install.lock");
    let Ok(lock) = std::fs::File::create(&lock_path) else { return };
    if lock.lock().is_err() || installed() {
        return;
    }
    // Any program makes check-gcode install rs274; its verdict is the tests' business.
    let program = std::env::temp_dir().join(format!("grainline-rs274-{}.ngc", std::process::id()));
    if std::fs::write(&program, "G21\nM2\n").is_ok() {
        let _ = std::process::Command::new("bash").arg(tool).arg(&program).output();
        let _ = std::fs::remove_file(&program);
    }
}

/// Runs a shared checker (`bash TOOL ARGS…`) and returns whether it accepted and what it
/// printed. A checker that *crashed* — LinuxCNC's rs274 dies of a bus error about once in a few
/// hundred runs on programs it accepts otherwise — is run again, at most twice more; a
/// rejection is never retried.
pub fn run_checker(tool: &std::path::Path, args: &[&std::ffi::OsStr]) -> (bool, String) {
    let mut text = String::new();
    for attempt in 0..3 {
        let out = std::process::Command::new("bash")
            .arg(tool)
            .args(args)
            .output()
            .expect("run shared tool");
        text = String::from_utf8_lossy(&out.stdout).to_string()
            + &String::from_utf8_lossy(&out.stderr);
        let crashed = ["Bus error", "Segmentation fault"].iter().any(|c| text.contains(c));
        if !crashed {
            return (out.status.success(), text);
        }
        eprintln!("{} crashed (attempt {}), trying again:\n{text}", tool.display(), attempt + 1);
    }
    (false, text)
}
