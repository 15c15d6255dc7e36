//! Which build of glint is running: the linker's build ID of the running
//! executable (the ELF note `NT_GNU_BUILD_ID`, a hash of the linked file),
//! shortened to 16 hex digits. Two builds of one version (a commit apart,
//! or the same source with another toolchain) have different IDs; the same
//! build always has the same one. Renders record it (`glint.build` in the
//! EXR, `glint_build` in `--stats`), so that `glint merge` can tell shards
//! of different builds apart where their version is the same.
//!
//! Read from the program headers already mapped in memory
//! (`dl_iterate_phdr`): no file is opened. None where the platform has no
//! such note or the linker wrote none.

use std::sync::OnceLock;

/// The running executable's build ID, 16 hex digits, or None.
pub fn build_id() -> Option<&'static str> {
    static ID: OnceLock<Option<String>> = OnceLock::new();
    ID.get_or_init(|| read().map(|bytes| hex(&bytes[..bytes.len().min(8)])))
        .as_deref()
}

/// `glint --version`'s text: the version and, where found, the build
/// (`0.1.0 (build 0123456789abcdef)`).
pub fn long_version() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| match build_id() {
        Some(b) => format!("{} (build {b})", env!("CARGO_PKG_VERSION")),
        None => env!("CARGO_PKG_VERSION").to_string(),
    })
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The descriptor of the first GNU build-ID note in `notes` (a PT_NOTE
/// segment: records of namesz, descsz, type, then the name and the
/// descriptor, each padded to 4 bytes).
pub fn parse_notes(notes: &[u8]) -> Option<Vec<u8>> {
    const NT_GNU_BUILD_ID: u32 = 3;
    let word = |at: usize| -> Option<u32> {
        Some(u32::from_ne_bytes(notes.get(at..at + 4)?.try_into().ok()?))
    };
    let pad = |n: usize| n.div_ceil(4) * 4;
    let mut at = 0usize;
    while at + 12 <= notes.len() {
        let namesz = word(at)? as usize;
        let descsz = word(at + 4)? as usize;
        let kind = word(at + 8)?;
        let name = at + 12;
        let desc = name.checked_add(pad(namesz))?;
        let end = desc.checked_add(pad(descsz))?;
        if kind == NT_GNU_BUILD_ID
            && notes.get(name..name.checked_add(namesz)?)? == b"GNU\0"
            && descsz > 0
        {
            return notes
                .get(desc..desc.checked_add(descsz)?)
                .map(<[u8]>::to_vec);
        }
        at = end;
    }
    None
}

#[cfg(target_os = "linux")]
fn read() -> Option<Vec<u8>> {
    use std::os::raw::{c_int, c_void};

    unsafe extern "C" fn visit(
        info: *mut libc::dl_phdr_info,
        _size: libc::size_t,
        data: *mut c_void,
    ) -> c_int {
        // SAFETY: the loader passes a valid dl_phdr_info for the duration
        // of the call, and `data` is the `Option<Vec<u8>>` below.
        let (info, out) = unsafe { (&*info, &mut *(data as *mut Option<Vec<u8>>)) };
        // The first object listed is the executable itself.
        for i in 0..info.dlpi_phnum as usize {
            // SAFETY: dlpi_phdr holds dlpi_phnum program headers.
            let ph = unsafe { &*info.dlpi_phdr.add(i) };
            if ph.p_type != libc::PT_NOTE {
                continue;
            }
            let addr = (info.dlpi_addr as usize).wrapping_add(ph.p_vaddr as usize);
            // SAFETY: a PT_NOTE segment of a loaded object is mapped,
            // readable, p_memsz bytes from its load address.
            let notes =
                unsafe { std::slice::from_raw_parts(addr as *const u8, ph.p_memsz as usize) };
            if let Some(id) = parse_notes(notes) {
                *out = Some(id);
                break;
            }
        }
        1 // stop after the executable
    }

    let mut out: Option<Vec<u8>> = None;
    // SAFETY: `visit` only reads what the loader hands it and writes `out`,
    // which outlives the call.
    unsafe { libc::dl_iterate_phdr(Some(visit), &mut out as *mut _ as *mut c_void) };
    out
}

#[cfg(not(target_os = "linux"))]
fn read() -> Option<Vec<u8>> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn note(kind: u32, name: &[u8], desc: &[u8]) -> Vec<u8> {
        let mut v = Vec::new();
        v.extend((name.len() as u32).to_ne_bytes());
        v.extend((desc.len() as u32).to_ne_bytes());
        v.extend(kind.to_ne_bytes());
        v.extend(name);
        v.resize(v.len().div_ceil(4) * 4, 0);
        v.extend(desc);
        v.resize(v.len().div_ceil(4) * 4, 0);
        v
    }

    #[test]
    fn finds_the_gnu_build_id_among_other_notes() {
        let id = [
            0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16,
        ];
        let mut notes = note(1, b"GNU\0", &[0; 16]); // NT_GNU_ABI_TAG
        notes.extend(note(3, b"Go\0", b"not this one"));
        notes.extend(note(3, b"GNU\0", &id));
        assert_eq!(parse_notes(&notes), Some(id.to_vec()));
        assert_eq!(hex(&id[..8]), "deadbeef01020304");
    }

    #[test]
    fn truncated_or_empty_notes_give_none() {
        let notes = note(3, b"GNU\0", &[7; 20]);
        assert_eq!(parse_notes(&notes[..notes.len() - 4]), None);
        assert_eq!(parse_notes(&notes[..10]), None);
        assert_eq!(parse_notes(&[]), None);
        assert_eq!(parse_notes(&note(3, b"GNU\0", &[])), None);
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn this_test_binary_has_a_build_id() {
        // Debian's linker writes one by default (`--build-id`); the tests'
        // own executable is linked like glint's.
        let id = build_id().expect("a build ID");
        assert_eq!(id.len(), 16);
        assert!(id.bytes().all(|b| b.is_ascii_hexdigit()), "{id}");
        assert_eq!(build_id(), Some(id));
    }
}
