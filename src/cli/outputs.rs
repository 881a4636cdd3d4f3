//! All-or-nothing outputs of a command: every file a command writes (mesh, report, picture,
//! levels, a grid and its `.json` sidecar) is first written into a hidden staging folder beside
//! its target (`.vesselmsr-XXXXXX/` in the target's folder, the file keeping its own name, so
//! writers that add a sidecar next to their file stage it too), and the staged files are renamed
//! onto their targets only when every output of the command was written. Dropping an
//! [`Outputs`] that was not committed (an error, a panic) removes the staging folders and the
//! folders it created; SIGINT, SIGTERM and SIGHUP remove them too ([`install_signal_cleanup`])
//! before the process exits with status 130.
//!
//! Renames within one folder are atomic and cannot run out of space, so once the commit starts
//! only an operating-system failure between two renames could leave part of the outputs. A
//! `kill -9` cannot be caught: it leaves the hidden staging folder behind, never a partial file
//! under a target's name.

use anyhow::Context as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The staging folders alive in this process, for the signal handler.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Prefix of the hidden staging folders.
const STAGING_PREFIX: &str = ".vesselmsr-";

/// Removes every live staging folder when the process gets SIGINT, SIGTERM or SIGHUP, then exits
/// with status 130. Installed once by the CLI; a second call does nothing.
pub fn install_signal_cleanup() {
    // An error means a handler is already installed (e.g. by a host program): leave it.
    let _ = ctrlc::set_handler(|| {
        // Holding the lock until exit also stops the main thread from staging anything new.
        let live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
        for dir in live.iter() {
            let _ = std::fs::remove_dir_all(dir);
        }
        std::process::exit(130);
    });
}

/// One staging folder: where it is and the folder its files go to.
struct Stage {
    folder: PathBuf,
    dir: PathBuf,
}

/// The outputs of one command (see the module documentation).
pub struct Outputs {
    stages: Vec<Stage>,
    /// Folders this command created for its outputs (deepest last), removed on failure.
    created: Vec<PathBuf>,
    committed: bool,
}

/// The folder a file path lives in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

impl Outputs {
    /// Checks the targets before any work is done: each file's folder exists and the file is not
    /// a folder; each folder of `dirs` is a folder or can be created under an existing folder;
    /// no path is named twice. Nothing is created yet.
    pub fn new(files: &[&Path], dirs: &[&Path]) -> anyhow::Result<Outputs> {
        let all: Vec<&Path> = files.iter().chain(dirs).copied().collect();
        for (i, a) in all.iter().enumerate() {
            anyhow::ensure!(
                !all[i + 1..].contains(a),
                "{}: named for two outputs",
                a.display()
            );
        }
        for file in files {
            anyhow::ensure!(
                file.file_name().is_some(),
                "{}: not a file name",
                file.display()
            );
            let folder = folder_of(file);
            anyhow::ensure!(
                folder.is_dir(),
                "{}: the folder {} does not exist",
                file.display(),
                folder.display()
            );
            anyhow::ensure!(!file.is_dir(), "{}: is a folder", file.display());
        }
        for dir in dirs {
            let existing = dir
                .ancestors()
                .find(|a| a.exists() || a.as_os_str().is_empty());
            match existing {
                Some(a) if a.as_os_str().is_empty() || a.is_dir() => {}
                Some(a) => anyhow::bail!(
                    "{}: cannot be a folder: {} is a file",
                    dir.display(),
                    a.display()
                ),
                None => {}
            }
        }
        Ok(Outputs {
            stages: Vec::new(),
            created: Vec::new(),
            committed: false,
        })
    }

    /// Creates the output folder `dir` (and missing parents), removed again if the command
    /// fails before [`Outputs::commit`].
    pub fn create_dir(&mut self, dir: &Path) -> anyhow::Result<()> {
        let mut missing: Vec<PathBuf> = dir
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        missing.reverse();
        for d in missing {
            std::fs::create_dir(&d).with_context(|| format!("{}", d.display()))?;
            self.created.push(d);
        }
        anyhow::ensure!(dir.is_dir(), "{}: not a folder", dir.display());
        Ok(())
    }

    /// Writes the output `target` through `write`, which is given the staged path to write (the
    /// same file name in the staging folder beside `target`). Errors name `target`.
    pub fn write<E: std::fmt::Display>(
        &mut self,
        target: &Path,
        write: impl FnOnce(&Path) -> Result<(), E>,
    ) -> anyhow::Result<()> {
        let name = target
            .file_name()
            .with_context(|| format!("{}: not a file name", target.display()))?;
        let dir = self.staging_dir(folder_of(target), target)?;
        let staged = dir.join(name);
        write(&staged).map_err(|e| {
            // Name the target, not the hidden staging path.
            let message = e
                .to_string()
                .replace(&staged.display().to_string(), &target.display().to_string());
            anyhow::anyhow!(message)
        })
    }

    /// The staging folder for files of `folder`, created on first use.
    fn staging_dir(&mut self, folder: &Path, target: &Path) -> anyhow::Result<PathBuf> {
        if let Some(s) = self.stages.iter().find(|s| s.folder == folder) {
            return Ok(s.dir.clone());
        }
        let mut live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
        let dir = tempfile::Builder::new()
            .prefix(STAGING_PREFIX)
            .tempdir_in(folder)
            .with_context(|| format!("{}", target.display()))?
            .keep();
        live.push(dir.clone());
        self.stages.push(Stage {
            folder: folder.to_path_buf(),
            dir: dir.clone(),
        });
        Ok(dir)
    }

    /// Renames every staged file onto its target (replacing an existing file) and removes the
    /// staging folders.
    pub fn commit(mut self) -> anyhow::Result<()> {
        for stage in &self.stages {
            let entries = std::fs::read_dir(&stage.dir)
                .with_context(|| format!("{}", stage.folder.display()))?;
            for entry in entries {
                let entry = entry.with_context(|| format!("{}", stage.folder.display()))?;
                let target = stage.folder.join(entry.file_name());
                std::fs::rename(entry.path(), &target)
                    .with_context(|| format!("{}", target.display()))?;
            }
        }
        self.committed = true;
        self.remove_stages();
        Ok(())
    }

    fn remove_stages(&mut self) {
        let mut live = LIVE.lock().unwrap_or_else(|p| p.into_inner());
        for stage in self.stages.drain(..) {
            let _ = std::fs::remove_dir_all(&stage.dir);
            live.retain(|d| d != &stage.dir);
        }
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        self.remove_stages();
        if !self.committed {
            for dir in self.created.iter().rev() {
                // Only if empty: never take away anything the user put there meanwhile.
                let _ = std::fs::remove_dir(dir);
            }
        }
    }
}
