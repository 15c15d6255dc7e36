//! Output files written whole or not at all.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use glint::cpu::film::temp_path_for;

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
        std::fs::File::create(&tmp).with_context(|| format!("{}: cannot write", path.display()))?;
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
        for i in 0..self.finals.len() {
            std::fs::rename(&self.temps[i], &self.finals[i])
                .with_context(|| format!("{}: cannot write", self.finals[i].display()))?;
            self.renamed = i + 1;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for (i, (t, f)) in self.temps.iter().zip(&self.finals).enumerate() {
            let _ = std::fs::remove_file(if i < self.renamed { f } else { t });
        }
    }
}
