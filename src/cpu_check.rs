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

    /// The CPUID words that hold the features below.
    #[derive(Clone, Copy)]
    pub(super) enum Word {
        /// Leaf 1, ecx.
        L1Ecx,
        /// Leaf 7 subleaf 0, ebx.
        L7Ebx,
        /// Leaf 7 subleaf 0, ecx.
        L7Ecx,
        /// Leaf 0x8000_0001, ecx.
        Ext1Ecx,
    }

    pub(super) struct Feature {
        pub name: &'static str,
        pub built_for: bool,
        pub word: Word,
        pub bit: u32,
        pub state: State,
        /// std's answer (`is_x86_feature_detected!`, which says true
        /// without asking where the build enabled the feature): the
        /// tests' reference for the bit above.
        #[cfg_attr(not(test), allow(dead_code))]
        pub std_detected: fn() -> bool,
    }

    macro_rules! features {
        ($(($f:tt, $word:ident, $bit:expr, $state:ident)),* $(,)?) => {
            [$(Feature {
                name: $f,
                built_for: cfg!(target_feature = $f),
                word: Word::$word,
                bit: $bit,
                state: State::$state,
                std_detected: || std::arch::is_x86_feature_detected!($f),
            }),*]
        };
    }

    /// The x86-64 features past the baseline that LLVM's CPU models enable
    /// (x86-64-v2 .. v4 and what `native` adds on current CPUs) with their
    /// CPUID bits (Intel SDM vol. 2A, CPUID).
    pub(super) fn table() -> [Feature; 32] {
        features![
            ("sse3", L1Ecx, 0, Sse),
            ("pclmulqdq", L1Ecx, 1, Sse),
            ("ssse3", L1Ecx, 9, Sse),
            ("fma", L1Ecx, 12, Avx),
            ("cmpxchg16b", L1Ecx, 13, Sse),
            ("sse4.1", L1Ecx, 19, Sse),
            ("sse4.2", L1Ecx, 20, Sse),
            ("movbe", L1Ecx, 22, Sse),
            ("popcnt", L1Ecx, 23, Sse),
            ("aes", L1Ecx, 25, Sse),
            ("xsave", L1Ecx, 26, Sse),
            ("avx", L1Ecx, 28, Avx),
            ("f16c", L1Ecx, 29, Avx),
            ("rdrand", L1Ecx, 30, Sse),
            ("bmi1", L7Ebx, 3, Sse),
            ("avx2", L7Ebx, 5, Avx),
            ("bmi2", L7Ebx, 8, Sse),
            ("avx512f", L7Ebx, 16, Avx512),
            ("avx512dq", L7Ebx, 17, Avx512),
            ("rdseed", L7Ebx, 18, Sse),
            ("adx", L7Ebx, 19, Sse),
            ("avx512ifma", L7Ebx, 21, Avx512),
            ("avx512cd", L7Ebx, 28, Avx512),
            ("sha", L7Ebx, 29, Sse),
            ("avx512bw", L7Ebx, 30, Avx512),
            ("avx512vl", L7Ebx, 31, Avx512),
            ("avx512vbmi", L7Ecx, 1, Avx512),
            ("avx512vbmi2", L7Ecx, 6, Avx512),
            ("avx512vnni", L7Ecx, 11, Avx512),
            ("avx512bitalg", L7Ecx, 12, Avx512),
            ("avx512vpopcntdq", L7Ecx, 14, Avx512),
            ("lzcnt", Ext1Ecx, 5, Sse),
        ]
    }

    /// This CPU's answers, asked once: the words above and XCR0 (0 where
    /// the OS has not enabled XSAVE).
    pub(super) struct Cpu {
        words: [u32; 4],
        xcr0: u64,
    }

    impl Cpu {
        /// (`__cpuid` is a safe function in newer Rust than the
        /// workspace's rust-version.)
        #[allow(unused_unsafe)]
        pub(super) fn read() -> Self {
            // SAFETY: CPUID exists on every x86-64 CPU; no leaf past the
            // highest one is asked.
            let (max, max_ext) = unsafe { (__cpuid(0).eax, __cpuid(0x8000_0000).eax) };
            let l1_ecx = unsafe { __cpuid(1).ecx };
            let l7 = (max >= 7).then(|| unsafe { __cpuid_count(7, 0) });
            let ext1_ecx = if max_ext >= 0x8000_0001 {
                unsafe { __cpuid(0x8000_0001).ecx }
            } else {
                0
            };
            // XGETBV only where OSXSAVE (leaf 1, ecx bit 27) says the OS
            // enabled it.
            let xcr0 = if l1_ecx & (1 << 27) != 0 {
                // SAFETY: as just said.
                unsafe { xcr0() }
            } else {
                0
            };
            Self {
                words: [
                    l1_ecx,
                    l7.map_or(0, |r| r.ebx),
                    l7.map_or(0, |r| r.ecx),
                    ext1_ecx,
                ],
                xcr0,
            }
        }

        /// Whether this CPU, and its OS's saved register state, have `f`.
        pub(super) fn has(&self, f: &Feature) -> bool {
            let need = match f.state {
                State::Sse => 0,
                State::Avx => 0b110,
                State::Avx512 => 0b1110_0110,
            };
            self.words[f.word as usize] & (1 << f.bit) != 0 && self.xcr0 & need == need
        }
    }

    #[target_feature(enable = "xsave")]
    unsafe fn xcr0() -> u64 {
        // SAFETY: the caller checked OSXSAVE.
        unsafe { _xgetbv(0) }
    }

    pub(super) fn built_for_but_missing() -> Vec<&'static str> {
        let mut built = table().into_iter().filter(|f| f.built_for).peekable();
        if built.peek().is_none() {
            return Vec::new(); // a baseline build asks the CPU nothing
        }
        let cpu = Cpu::read();
        built.filter(|f| !cpu.has(f)).map(|f| f.name).collect()
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
        let cpu = x86::Cpu::read();
        for f in x86::table() {
            if f.built_for {
                continue; // std answers true without asking
            }
            assert_eq!(cpu.has(&f), (f.std_detected)(), "{}", f.name);
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
