//! Output files written whole or not at all.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, anyhow, bail};
use glint::cpu::safe_fs::{create_temp_beside, describe};

/// Every temporary not yet renamed or removed, for the signal handler
/// (`on_signal`): SIGINT/SIGTERM must not leave `.NAME.tmp-PID` files.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

fn forget(paths: &[PathBuf]) {
    pending().retain(|p| !paths.contains(p));
}

/// Remove every pending temporary, then exit with one line: the
/// conventional 128 + signal number. The lock is held to the end, so a
/// commit in progress finishes its renames first (its files are then
/// whole and stay) and none starts after.
pub fn on_signal(name: &str, number: i32) -> ! {
    let mut p = pending();
    for t in p.drain(..) {
        let _ = std::fs::remove_file(&t);
    }
    eprintln!("glint: interrupted by {name}; unfinished outputs removed");
    std::process::exit(128 + number)
}

/// Standard output was closed under us (`glint diff ... | head -1`): what a
/// Unix filter does on SIGPIPE, quietly. Temporaries are removed (no output
/// is presented as complete) and the exit status is 128 + SIGPIPE.
pub fn on_broken_pipe() -> ! {
    for t in pending().drain(..) {
        let _ = std::fs::remove_file(&t);
    }
    std::process::exit(128 + 13)
}

/// Output files in two phases: temporaries beside each final path are
/// created up front (so an unwritable destination fails before any
/// rendering), filled at the end, then renamed. Dropping the set without
/// `commit` removes every temporary and every file already renamed.
///
/// Each temporary is created exclusively (`O_CREAT | O_EXCL`, a random
/// name: `glint_cpu::safe_fs::create_temp_beside`) and written through the
/// descriptor that created it, so a file or link planted in a shared folder
/// is never opened. A final path that exists and is not a regular file (a
/// device such as `/dev/null`, a FIFO, a directory, or a link to one) is
/// refused: renaming over it would replace the node.
pub struct Outputs {
    finals: Vec<PathBuf>,
    temps: Vec<PathBuf>,
    files: Vec<Option<std::fs::File>>,
    renamed: usize,
    committed: bool,
}

/// Where a path's file lives once written: its folder's real path and its
/// name (links in the folder resolved, the name itself not: renaming
/// replaces a link, not its target).
fn target_key(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(dir).ok()?.join(name))
}

/// Whether writing `out` could replace or change `input`: the same place
/// once written, or the same existing file (links followed).
pub fn names_same(out: &Path, input: &Path) -> bool {
    if super::same_file(out, input) {
        return true;
    }
    match (target_key(out), std::fs::canonicalize(input).ok()) {
        (Some(o), Some(i)) => o == i || target_key(input).is_some_and(|k| k == o),
        _ => false,
    }
}

/// Refuse an output path that is not (and does not lead to) a regular file.
fn check_target(path: &Path) -> Result<()> {
    let p = path.display();
    let Ok(link) = std::fs::symlink_metadata(path) else {
        return Ok(());
    };
    let meta = if link.file_type().is_symlink() {
        match std::fs::metadata(path) {
            Ok(m) => m,
            // A dangling link: the rename replaces the link itself.
            Err(_) => return Ok(()),
        }
    } else {
        link
    };
    if meta.is_file() {
        return Ok(());
    }
    bail!(
        "{p}: {}; glint writes outputs only as regular files (refusing to replace it)",
        describe(meta.file_type())
    )
}

impl Outputs {
    pub fn new() -> Self {
        Self {
            finals: Vec::new(),
            temps: Vec::new(),
            files: Vec::new(),
            renamed: 0,
            committed: false,
        }
    }

    /// Reserve `path`: create its temporary now. A path that names the
    /// same file as one already reserved (`out.exr` and `./out.exr`) is
    /// refused: the two renames would race for one name.
    pub fn reserve(&mut self, path: &Path) -> Result<usize> {
        if let Some(other) = self.finals.iter().find(|p| names_same(path, p)) {
            bail!(
                "{}: given twice as an output (also as {})",
                path.display(),
                other.display()
            );
        }
        check_target(path)?;
        // Registered under the pending lock as soon as it exists, so a
        // signal still removes it.
        let mut p = pending();
        let (file, tmp) = create_temp_beside(path).map_err(|e| {
            // The usual cause, said plainly (the error itself names the
            // temporary, a path the user never gave).
            let dir = path
                .parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            if dir.is_dir() {
                anyhow!(e).context(format!("{}: cannot write", path.display()))
            } else {
                anyhow!(
                    "{}: cannot write: no folder {}",
                    path.display(),
                    dir.display()
                )
            }
        })?;
        p.push(tmp.clone());
        drop(p);
        self.finals.push(path.to_path_buf());
        self.temps.push(tmp);
        self.files.push(Some(file));
        Ok(self.finals.len() - 1)
    }

    /// Refuse outputs that would overwrite one of `inputs` (the scene's
    /// buffers and images, the environment map), before anything renders.
    pub fn refuse_inputs(&self, inputs: &[PathBuf]) -> Result<()> {
        for f in &self.finals {
            if let Some(i) = inputs.iter().find(|i| names_same(f, i)) {
                bail!(
                    "{}: is an input ({}); refusing to overwrite it",
                    f.display(),
                    i.display()
                );
            }
        }
        Ok(())
    }

    pub fn write(
        &mut self,
        i: usize,
        f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
    ) -> Result<()> {
        let path = &self.finals[i];
        let file = self.files[i]
            .take()
            .ok_or_else(|| anyhow!("{}: written twice", path.display()))?;
        let mut w = std::io::BufWriter::new(file);
        f(&mut w).with_context(|| format!("{}", path.display()))?;
        let file = w
            .into_inner()
            .map_err(|e| anyhow!("{}: {}", path.display(), e.error()))?;
        file.sync_all()
            .with_context(|| format!("{}: cannot write", path.display()))?;
        Ok(())
    }

    /// Rename every temporary over its final path.
    pub fn commit(mut self) -> Result<()> {
        // Held through the renames: a signal waits for them.
        let mut p = pending();
        let mut result = Ok(());
        for i in 0..self.finals.len() {
            if let Err(e) = std::fs::rename(&self.temps[i], &self.finals[i]) {
                result =
                    Err(anyhow!(e).context(format!("{}: cannot write", self.finals[i].display())));
                break;
            }
            self.renamed = i + 1;
        }
        if result.is_ok() {
            p.retain(|t| !self.temps.contains(t));
            self.committed = true;
        }
        // Released before `drop` cleans up after a failure.
        drop(p);
        result
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        forget(&self.temps);
        for (i, (t, f)) in self.temps.iter().zip(&self.finals).enumerate() {
            let _ = std::fs::remove_file(if i < self.renamed { f } else { t });
        }
    }
}
