//! Files as a hostile folder may hold them: inputs that could block or are
//! not files, temporaries an attacker could plant, and how much memory the
//! machine can actually give.
//!
//! - [`open_regular`] opens with `O_NONBLOCK | O_NOCTTY` and checks the
//!   opened descriptor (`fstat`), so a FIFO or a device is refused without
//!   waiting for a writer and without a window between check and open.
//! - [`create_temp_beside`] creates `.NAME.tmp-PID.XXXXXX` beside the final
//!   path with `O_CREAT | O_EXCL` (the `tempfile` crate's builder): a planted
//!   file or link of any name is never opened, so a rename can only ever put
//!   glint's own bytes under the final name.
//! - [`available_memory`] is the least of `MemAvailable`, the cgroup's
//!   remaining limit and the address space `RLIMIT_AS` leaves.

use std::fs::File;
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// What a file type is, for messages ("not a regular file" alone says too
/// little).
pub fn describe(t: std::fs::FileType) -> &'static str {
    if t.is_file() {
        "a regular file"
    } else if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a named pipe (FIFO)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Open `path` for reading only if it is a regular file (links followed).
/// The open itself cannot block (`O_NONBLOCK`: a FIFO opens at once, a
/// device's driver is not asked to wait) and the type is read from the
/// opened descriptor. Errors are one phrase without the path.
pub fn open_regular(path: &Path) -> Result<File, String> {
    // Refuse by name first where the type is plain, so a device is not
    // even opened (opening some devices has effects).
    if let Ok(m) = std::fs::metadata(path)
        && !m.is_file()
    {
        return Err(format!("{}, not a regular file", describe(m.file_type())));
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(|e| format!("cannot open: {e}"))?;
    let meta = file.metadata().map_err(|e| format!("cannot read: {e}"))?;
    if !meta.is_file() {
        return Err(format!(
            "{}, not a regular file",
            describe(meta.file_type())
        ));
    }
    // O_NONBLOCK means nothing for a regular file's reads on Linux; it is
    // left set.
    Ok(file)
}

/// The bytes of a regular file of at most `limit` bytes ([`open_regular`]).
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let mut file = open_regular(path)?;
    let len = file
        .metadata()
        .map_err(|e| format!("cannot read: {e}"))?
        .len();
    if len > limit {
        return Err(format!(
            "file is {len} bytes; glint reads up to {limit} bytes here"
        ));
    }
    let mut out = Vec::with_capacity(len as usize);
    // `take`: a file that grows while read cannot push past the limit.
    file.by_ref()
        .take(limit + 1)
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot read: {e}"))?;
    if out.len() as u64 > limit {
        return Err(format!("file grew past {limit} bytes while read"));
    }
    Ok(out)
}

/// The prefix of every temporary for `path`: `.NAME.tmp-PID.` (hidden, and
/// the process that owns it is visible in its name).
pub fn temp_prefix(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!(".{name}.tmp-{}.", std::process::id())
}

/// Create a new, empty temporary beside `path` (same folder, so the final
/// rename stays on one file system), exclusively: `O_CREAT | O_EXCL`, a
/// random suffix, mode 0666 less the umask. Returns the open file and its path; the caller
/// renames it over `path` when complete or removes it.
pub fn create_temp_beside(path: &Path) -> std::io::Result<(File, PathBuf)> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    // 0666 less the umask, as `File::create` would make the final file;
    // exclusivity, not the mode, is what keeps planted files out.
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::Builder::new()
        .prefix(&temp_prefix(path))
        .suffix("")
        .rand_bytes(6)
        .permissions(std::fs::Permissions::from_mode(0o666))
        .tempfile_in(dir)?;
    // Kept: the caller owns removal (signal handlers need the path).
    tmp.keep().map_err(|e| e.error)
}

/// Write `bytes` to `path` whole or not at all: an exclusive temporary
/// beside it ([`create_temp_beside`]), synced, then renamed over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let (mut file, tmp) = create_temp_beside(path)?;
    let result = file
        .write_all(bytes)
        .and_then(|_| file.sync_all())
        .and_then(|_| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Bytes this process can still allocate, as far as the machine says:
/// the least of `/proc/meminfo`'s MemAvailable, the cgroup v2 limit less
/// its usage, and `RLIMIT_AS` less the address space in use. `None` when
/// nothing is known (no /proc).
pub fn available_memory() -> Option<u64> {
    let mut best: Option<u64> = None;
    let mut take = |v: u64| best = Some(best.map_or(v, |b| b.min(v)));
    let kib = |text: &str, key: &str| -> Option<u64> {
        text.lines()
            .find(|l| l.starts_with(key))?
            .split_whitespace()
            .nth(1)?
            .parse::<u64>()
            .ok()
            .map(|k| k * 1024)
    };
    if let Ok(m) = std::fs::read_to_string("/proc/meminfo")
        && let Some(v) = kib(&m, "MemAvailable:")
    {
        take(v);
    }
    if let Some(v) = cgroup_room() {
        take(v);
    }
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) } == 0
        && lim.rlim_cur != libc::RLIM_INFINITY
    {
        let used = std::fs::read_to_string("/proc/self/status")
            .ok()
            .and_then(|s| kib(&s, "VmSize:"))
            .unwrap_or(0);
        take(lim.rlim_cur.saturating_sub(used));
    }
    best
}

/// The cgroup v2 memory limit of this process less its usage.
fn cgroup_room() -> Option<u64> {
    let cg = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let rel = cg.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = Path::new("/sys/fs/cgroup").join(rel.trim_start_matches('/'));
    let max = std::fs::read_to_string(dir.join("memory.max")).ok()?;
    let max = max.trim().parse::<u64>().ok()?;
    let cur = std::fs::read_to_string(dir.join("memory.current"))
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .unwrap_or(0);
    Some(max.saturating_sub(cur))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("f.exr");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = read_regular(&fifo, 1 << 20).unwrap_err();
        assert!(e.contains("named pipe"), "{e}");
    }

    #[test]
    fn temporaries_never_reuse_a_planted_name() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, "keep").unwrap();
        let out = dir.path().join("out.exr");
        // Plant links under every name the old scheme would have used.
        let plain = dir
            .path()
            .join(format!(".out.exr.tmp-{}", std::process::id()));
        std::os::unix::fs::symlink(&victim, &plain).unwrap();
        write_atomic(&out, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep");
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert!(std::fs::symlink_metadata(&out).unwrap().is_file());
    }

    #[test]
    fn memory_is_known_on_linux() {
        let m = available_memory().expect("Linux has /proc/meminfo");
        assert!(m > 0);
    }
}
