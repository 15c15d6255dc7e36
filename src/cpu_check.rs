//! The CPU the binary was built for against the one it runs on.
//! `scripts/build.sh` builds for the machine it runs on (`-C
//! target-cpu=native`: its AVX2, FMA or AVX-512 throughout, not only in
//! the kernels that detect them at run time), which is faster and gives the
//! same images bit for bit (docs/benchmarks.md). Such a binary copied to an
//! older CPU would die of an illegal instruction somewhere in a render; it
//! says so in one line before it starts instead. (The check is compiled
//! for the same CPU: on one without AVX, from before 2011, it cannot run
//! either.)
//!
//! The CPU is asked with CPUID itself: `is_x86_feature_detected!` answers
//! true, without asking, for every feature the build enabled.

/// The one-line refusal where this CPU lacks features the binary was
/// built to use; None where it has them all.
pub fn refusal() -> Option<String> {
    message(&x86::built_for_but_missing())
}

fn message(missing: &[&str]) -> Option<String> {
    const NAMED: usize = 4;
    (!missing.is_empty()).then(|| {
        let mut names = missing[..missing.len().min(NAMED)].join(", ");
        if missing.len() > NAMED {
            names += &format!(" and {} more", missing.len() - NAMED);
        }
        format!(
            "this binary was built for a CPU with {names}, which this one lacks: build it on \
             this machine (scripts/build.sh), or with GLINT_TARGET_CPU=x86-64 for a binary that \
             runs on any x86-64"
        )
    })
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};

    /// Register state the OS must save for a feature's registers (XCR0).
    #[derive(Clone, Copy)]
    pub(super) enum State {
        /// The baseline's XMM registers.
        Sse,
        /// YMM: XCR0 bits 1 and 2.
        Avx,
        /// ZMM and the mask registers: XCR0 bits 1, 2 and 5-7.
        Avx512,
    }

    /// Where CPUID reports a feature: (leaf, subleaf, register 0-3 for
    /// eax, ebx, ecx, edx, bit).
    pub(super) struct Feature {
        pub name: &'static str,
        pub built_for: bool,
        pub at: (u32, u32, usize, u32),
        pub state: State,
    }

    macro_rules! features {
        ($(($f:tt, $leaf:expr, $sub:expr, $reg:expr, $bit:expr, $state:ident)),* $(,)?) => {
            [$(Feature {
                name: $f,
                built_for: cfg!(target_feature = $f),
                at: ($leaf, $sub, $reg, $bit),
                state: State::$state,
            }),*]
        };
    }

    const ECX: usize = 2;
    const EBX: usize = 1;

    /// The x86-64 features past the baseline that LLVM's CPU models enable
    /// (x86-64-v2 .. v4 and what `native` adds on current CPUs) with their
    /// CPUID bits (Intel SDM vol. 2A, CPUID).
    pub(super) fn table() -> [Feature; 32] {
        features![
            ("sse3", 1, 0, ECX, 0, Sse),
            ("pclmulqdq", 1, 0, ECX, 1, Sse),
            ("ssse3", 1, 0, ECX, 9, Sse),
            ("fma", 1, 0, ECX, 12, Avx),
            ("cmpxchg16b", 1, 0, ECX, 13, Sse),
            ("sse4.1", 1, 0, ECX, 19, Sse),
            ("sse4.2", 1, 0, ECX, 20, Sse),
            ("movbe", 1, 0, ECX, 22, Sse),
            ("popcnt", 1, 0, ECX, 23, Sse),
            ("aes", 1, 0, ECX, 25, Sse),
            ("xsave", 1, 0, ECX, 26, Sse),
            ("avx", 1, 0, ECX, 28, Avx),
            ("f16c", 1, 0, ECX, 29, Avx),
            ("rdrand", 1, 0, ECX, 30, Sse),
            ("bmi1", 7, 0, EBX, 3, Sse),
            ("avx2", 7, 0, EBX, 5, Avx),
            ("bmi2", 7, 0, EBX, 8, Sse),
            ("avx512f", 7, 0, EBX, 16, Avx512),
            ("avx512dq", 7, 0, EBX, 17, Avx512),
            ("rdseed", 7, 0, EBX, 18, Sse),
            ("adx", 7, 0, EBX, 19, Sse),
            ("avx512ifma", 7, 0, EBX, 21, Avx512),
            ("avx512cd", 7, 0, EBX, 28, Avx512),
            ("sha", 7, 0, EBX, 29, Sse),
            ("avx512bw", 7, 0, EBX, 30, Avx512),
            ("avx512vl", 7, 0, EBX, 31, Avx512),
            ("avx512vbmi", 7, 0, ECX, 1, Avx512),
            ("avx512vbmi2", 7, 0, ECX, 6, Avx512),
            ("avx512vnni", 7, 0, ECX, 11, Avx512),
            ("avx512bitalg", 7, 0, ECX, 12, Avx512),
            ("avx512vpopcntdq", 7, 0, ECX, 14, Avx512),
            ("lzcnt", 0x8000_0001, 0, ECX, 5, Sse),
        ]
    }

    /// Whether this CPU (and its OS) has `f`. (`__cpuid` is a safe
    /// function in newer Rust than the workspace's rust-version.)
    #[allow(unused_unsafe)]
    pub(super) fn has(f: &Feature) -> bool {
        let (leaf, sub, reg, bit) = f.at;
        // SAFETY: CPUID exists on every x86-64 CPU; a leaf past the highest
        // one is not asked.
        let max = unsafe { __cpuid(leaf & 0x8000_0000).eax };
        if leaf > max {
            return false;
        }
        let r = unsafe { __cpuid_count(leaf, sub) };
        let words = [r.eax, r.ebx, r.ecx, r.edx];
        words[reg] & (1 << bit) != 0 && state_saved(f.state)
    }

    #[allow(unused_unsafe)]
    fn state_saved(state: State) -> bool {
        let need = match state {
            State::Sse => return true,
            State::Avx => 0b110,
            State::Avx512 => 0b1110_0110,
        };
        // SAFETY: CPUID as above; XGETBV only where OSXSAVE (leaf 1, ecx
        // bit 27) says the OS enabled it.
        let osxsave = unsafe { __cpuid(1).ecx } & (1 << 27) != 0;
        osxsave && unsafe { xcr0() } & need == need
    }

    #[target_feature(enable = "xsave")]
    unsafe fn xcr0() -> u64 {
        // SAFETY: the caller checked OSXSAVE.
        unsafe { _xgetbv(0) }
    }

    pub(super) fn built_for_but_missing() -> Vec<&'static str> {
        table()
            .iter()
            .filter(|f| f.built_for && !has(f))
            .map(|f| f.name)
            .collect()
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod x86 {
    pub(super) fn built_for_but_missing() -> Vec<&'static str> {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_build_machine_has_what_it_built_for() {
        assert_eq!(refusal(), None);
    }

    /// The table's CPUID bits against std's detection, on a build that
    /// leaves the features to run-time detection (the test profile's).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn cpuid_bits_agree_with_std_detection() {
        macro_rules! std_has {
            ($name:expr, $($f:tt),*) => {
                match $name {
                    $($f => std::arch::is_x86_feature_detected!($f),)*
                    other => panic!("{other} is not in the test's list"),
                }
            };
        }
        for f in x86::table() {
            if f.built_for {
                continue; // std answers true without asking
            }
            let std = std_has!(
                f.name,
                "sse3",
                "pclmulqdq",
                "ssse3",
                "fma",
                "cmpxchg16b",
                "sse4.1",
                "sse4.2",
                "movbe",
                "popcnt",
                "aes",
                "xsave",
                "avx",
                "f16c",
                "rdrand",
                "bmi1",
                "avx2",
                "bmi2",
                "avx512f",
                "avx512dq",
                "rdseed",
                "adx",
                "avx512ifma",
                "avx512cd",
                "sha",
                "avx512bw",
                "avx512vl",
                "avx512vbmi",
                "avx512vbmi2",
                "avx512vnni",
                "avx512bitalg",
                "avx512vpopcntdq",
                "lzcnt"
            );
            assert_eq!(x86::has(&f), std, "{}", f.name);
        }
    }

    #[test]
    fn a_missing_feature_is_named_in_one_line() {
        assert_eq!(message(&[]), None);
        let m = message(&["avx512f", "avx512bw"]).unwrap();
        assert!(m.contains("with avx512f, avx512bw, which"), "{m}");
        assert!(!m.contains('\n'));
        let m = message(&["a", "b", "c", "d", "e", "f"]).unwrap();
        assert!(m.contains("with a, b, c, d and 2 more, which"), "{m}");
    }
}
