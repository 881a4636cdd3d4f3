//! The command-line interface.

/// Runs the CLI and returns the process exit status.
pub fn run() -> i32 {
    0
}
