//! Output files written whole or not at all.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, anyhow, bail};
use glint::cpu::film::temp_path_for;

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

/// Output files in two phases: temporaries beside each final path are
/// created up front (so an unwritable destination fails before any
/// rendering), filled at the end, then renamed. Dropping the set without
/// `commit` removes every temporary and every file already renamed.
pub struct Outputs {
    finals: Vec<PathBuf>,
    temps: Vec<PathBuf>,
    renamed: usize,
    committed: bool,
}

impl Outputs {
    pub fn new() -> Self {
        Self {
            finals: Vec::new(),
            temps: Vec::new(),
            renamed: 0,
            committed: false,
        }
    }

    /// Reserve `path`: create its temporary now.
    pub fn reserve(&mut self, path: &Path) -> Result<usize> {
        if let Some(i) = self.finals.iter().position(|p| p == path) {
            return Ok(i);
        }
        if path.is_dir() {
            bail!("{}: is a directory", path.display());
        }
        let tmp = temp_path_for(path);
        // Registered before it exists, so a signal between the two still
        // removes it.
        pending().push(tmp.clone());
        if let Err(e) = std::fs::File::create(&tmp) {
            forget(std::slice::from_ref(&tmp));
            return Err(anyhow!(e).context(format!("{}: cannot write", path.display())));
        }
        self.finals.push(path.to_path_buf());
        self.temps.push(tmp);
        Ok(self.finals.len() - 1)
    }

    pub fn write(
        &self,
        i: usize,
        f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
    ) -> Result<()> {
        let path = &self.finals[i];
        let file = std::fs::File::create(&self.temps[i])
            .with_context(|| format!("{}: cannot write", path.display()))?;
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
