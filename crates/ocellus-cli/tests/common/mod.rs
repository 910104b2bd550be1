//! Helpers shared by the CLI tests: the binary, a fresh temporary folder, a run that must
//! succeed.
// Each test binary uses its own subset.
#![allow(dead_code, clippy::unwrap_used)]

use std::path::PathBuf;
use std::process::Command;

/// The `ocellus` binary under test.
pub fn ocellus() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ocellus"))
}

/// An empty folder of the system's temporary directory, named after the process and `name`.
pub fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ocellus-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `cmd`, asserts it succeeded (showing its stderr otherwise) and returns its stdout.
pub fn run(cmd: &mut Command) -> String {
    let o = cmd.output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}
