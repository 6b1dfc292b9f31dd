//! The SIMD level of the kernels: detected once, capped by the `VISPRIM_SIMD` variable.
//!
//! The crate is built for baseline x86-64; the kernels choose at run time between portable
//! code and code compiled for wider instruction sets (`#[target_feature(enable = ...)]`). This
//! module is the only place that asks the CPU (a test keeps it so). A level requires every
//! feature that a kernel compiled for it enables, and what rustc enables with them: AVX-512F
//! implies AVX2, FMA and F16C, which the compiler may then use too.
//!
//! | level | `VISPRIM_SIMD` | requires |
//! |---|---|---|
//! | [`Level::Portable`] | `portable` | nothing (plain Rust, any CPU) |
//! | [`Level::Avx2Fma`] | `avx2` | avx2, fma |
//! | [`Level::Avx512`] | `avx512` | avx512f, avx512vl, avx2, fma, f16c |
//!
//! `VISPRIM_SIMD` (read once, at the first kernel call) caps the level at one the CPU has;
//! unset or empty means the best the CPU has. An unknown value, or a level the CPU lacks, is an
//! error from [`level`] that names the variable, its value and the CPU's best level; every
//! kernel entry point that chooses an instruction set returns it (the Python binding raises
//! `ValueError`).

use std::sync::OnceLock;

use crate::{Error, Result};

/// The environment variable that caps the level.
pub const ENV: &str = "VISPRIM_SIMD";

/// A SIMD level, ordered: each one's features include those of the levels below.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Level {
    /// Plain Rust (`f64::mul_add` where the kernels need a fused multiply-add).
    Portable,
    /// AVX2 with FMA: 4 doubles per vector.
    Avx2Fma,
    /// AVX-512F (with AVX-512VL for 256-bit operations): 8 doubles per vector.
    Avx512,
}

impl Level {
    /// Every level, lowest first.
    pub const ALL: [Level; 3] = [Level::Portable, Level::Avx2Fma, Level::Avx512];

    /// The value of `VISPRIM_SIMD` that selects this level.
    pub fn name(self) -> &'static str {
        match self {
            Level::Portable => "portable",
            Level::Avx2Fma => "avx2",
            Level::Avx512 => "avx512",
        }
    }

    /// The instruction set as `instruction_set()` reports it: `"portable"`, `"avx2+fma"` or
    /// `"avx512f"`.
    pub fn instruction_set(self) -> &'static str {
        match self {
            Level::Portable => "portable",
            Level::Avx2Fma => "avx2+fma",
            Level::Avx512 => "avx512f",
        }
    }

    /// The CPU features this level requires (names of `is_x86_feature_detected!`): the union
    /// of the `target_feature` lists of the kernels compiled for it, with their implications.
    pub fn features(self) -> &'static [&'static str] {
        match self {
            Level::Portable => &[],
            Level::Avx2Fma => &["avx2", "fma"],
            Level::Avx512 => &["avx512f", "avx512vl", "avx2", "fma", "f16c"],
        }
    }

    /// The level named `name` (a value of `VISPRIM_SIMD`).
    pub fn from_name(name: &str) -> Option<Level> {
        Level::ALL.into_iter().find(|l| l.name() == name)
    }
}

/// Whether this CPU (and the operating system, for the vector registers' state) has `feature`.
#[cfg(target_arch = "x86_64")]
fn cpu_has(feature: &str) -> bool {
    match feature {
        "avx2" => std::arch::is_x86_feature_detected!("avx2"),
        "fma" => std::arch::is_x86_feature_detected!("fma"),
        "f16c" => std::arch::is_x86_feature_detected!("f16c"),
        "avx512f" => std::arch::is_x86_feature_detected!("avx512f"),
        "avx512vl" => std::arch::is_x86_feature_detected!("avx512vl"),
        _ => false,
    }
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has(_feature: &str) -> bool {
    false
}

/// The highest level whose features all pass `has`.
fn best_with(has: &dyn Fn(&str) -> bool) -> Level {
    Level::ALL
        .into_iter()
        .rev()
        .find(|l| l.features().iter().all(|f| has(f)))
        .unwrap_or(Level::Portable)
}

/// The level a `VISPRIM_SIMD` setting (`None`: unset) gives on a CPU whose features pass
/// `has`, or the message of the error.
fn choose(setting: Option<&str>, has: &dyn Fn(&str) -> bool) -> std::result::Result<Level, String> {
    let best = best_with(has);
    let usable = Level::ALL
        .into_iter()
        .filter(|&l| l <= best)
        .map(Level::name)
        .collect::<Vec<_>>()
        .join(", ");
    let Some(value) = setting.filter(|s| !s.is_empty()) else {
        return Ok(best);
    };
    let Some(level) = Level::from_name(value) else {
        return Err(format!(
            "{ENV}={value:?} is not a SIMD level: use portable, avx2 or avx512 (this CPU's best \
             is {}), or unset {ENV}",
            best.name()
        ));
    };
    let missing: Vec<&str> = level
        .features()
        .iter()
        .copied()
        .filter(|f| !has(f))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "{ENV}={value} asks for a level this CPU lacks: it has no {} (its best level is {}); \
             use {usable}, or unset {ENV}",
            missing.join(", "),
            best.name()
        ));
    }
    Ok(level)
}

/// The level the kernels run at: the CPU's best, capped by `VISPRIM_SIMD` (read once).
///
/// Errors: `VISPRIM_SIMD` is not one of `portable`, `avx2`, `avx512`, or names a level this
/// CPU lacks (InvalidArgument, naming the variable, its value and the CPU's best level).
pub fn level() -> Result<Level> {
    chosen().clone().map_err(Error::InvalidArgument)
}

fn chosen() -> &'static std::result::Result<Level, String> {
    static CHOSEN: OnceLock<std::result::Result<Level, String>> = OnceLock::new();
    CHOSEN.get_or_init(|| match std::env::var_os(ENV) {
        None => choose(None, &cpu_has),
        Some(v) => match v.to_str() {
            Some(s) => choose(Some(s), &cpu_has),
            None => Err(format!("{ENV}={v:?} is not a SIMD level (not UTF-8)")),
        },
    })
}

/// [`level`] for the dispatch inside kernels whose entry point has already called [`level`]
/// (so the setting is valid); [`Level::Portable`] if it is not.
pub fn active() -> Level {
    match chosen() {
        Ok(level) => *level,
        Err(_) => Level::Portable,
    }
}

/// The levels up to the active one, lowest first: the ones tests and benchmarks compare.
pub fn levels() -> Vec<Level> {
    let top = active();
    Level::ALL.into_iter().filter(|&l| l <= top).collect()
}

/// The best level this CPU runs (detected once).
fn best() -> Level {
    static BEST: OnceLock<Level> = OnceLock::new();
    *BEST.get_or_init(|| best_with(&cpu_has))
}

/// Every level this CPU runs, lowest first, whatever `VISPRIM_SIMD` says.
pub fn supported() -> Vec<Level> {
    Level::ALL.into_iter().filter(|&l| l <= best()).collect()
}

/// Whether this CPU runs `level` (the safety condition of the kernels compiled for it).
pub fn cpu_runs(level: Level) -> bool {
    level <= best()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu(features: &'static [&'static str]) -> impl Fn(&str) -> bool {
        move |f| features.contains(&f)
    }

    const AVX2_CPU: &[&str] = &["avx2", "fma", "f16c"];
    const AVX512_CPU: &[&str] = &["avx2", "fma", "f16c", "avx512f", "avx512vl"];

    #[test]
    fn the_best_level_needs_every_feature() {
        assert_eq!(best_with(&cpu(&[])), Level::Portable);
        assert_eq!(best_with(&cpu(&["avx2"])), Level::Portable);
        assert_eq!(best_with(&cpu(AVX2_CPU)), Level::Avx2Fma);
        assert_eq!(best_with(&cpu(AVX512_CPU)), Level::Avx512);
        // AVX-512F without VL (Xeon Phi) runs the AVX2 kernels only.
        let phi = cpu(&["avx2", "fma", "f16c", "avx512f"]);
        assert_eq!(best_with(&phi), Level::Avx2Fma);
    }

    #[test]
    fn the_setting_caps_the_level() {
        let c = cpu(AVX512_CPU);
        assert_eq!(choose(None, &c), Ok(Level::Avx512));
        assert_eq!(choose(Some(""), &c), Ok(Level::Avx512));
        for level in Level::ALL {
            assert_eq!(choose(Some(level.name()), &c), Ok(level));
        }
        assert_eq!(choose(Some("portable"), &cpu(&[])), Ok(Level::Portable));
    }

    #[test]
    fn a_level_the_cpu_lacks_is_an_error_naming_what_is_missing() {
        let err = choose(Some("avx512"), &cpu(AVX2_CPU)).unwrap_err();
        assert_eq!(
            err,
            "VISPRIM_SIMD=avx512 asks for a level this CPU lacks: it has no avx512f, avx512vl \
             (its best level is avx2); use portable, avx2, or unset VISPRIM_SIMD"
        );
        let err = choose(Some("avx2"), &cpu(&["avx2"])).unwrap_err();
        assert!(
            err.contains("it has no fma (its best level is portable)"),
            "{err}"
        );
    }

    #[test]
    fn an_unknown_value_is_an_error() {
        for bad in ["AVX2", "avx2+fma", "sse4", " portable", "1"] {
            let err = choose(Some(bad), &cpu(AVX2_CPU)).unwrap_err();
            assert!(
                err.starts_with(&format!("VISPRIM_SIMD={bad:?} is not")),
                "{err}"
            );
            assert!(err.contains("this CPU's best is avx2"), "{err}");
        }
    }

    #[test]
    fn the_setting_of_this_run_is_valid() {
        // `VISPRIM_SIMD=<level> cargo test` runs every kernel test at that level; a level this
        // CPU lacks fails here with the message the kernels return.
        if let Err(e) = level() {
            panic!("{e}");
        }
        assert_eq!(levels().last(), Some(&active()));
        assert!(levels().iter().all(|&l| cpu_runs(l)));
    }

    #[test]
    fn lower_levels_need_a_subset_of_the_features() {
        for pair in Level::ALL.windows(2) {
            let (lo, hi) = (pair[0], pair[1]);
            assert!(lo.features().iter().all(|f| hi.features().contains(f)));
        }
    }

    /// Every `target_feature` list in the crate, and every feature named as a string literal,
    /// is covered by the level that runs it, and no other module asks the CPU.
    #[test]
    fn this_module_is_the_only_detection_and_covers_every_enabled_feature() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("rust/src");
        let mut files = Vec::new();
        let mut stack = vec![dir.clone()];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    files.push(p);
                }
            }
        }
        assert!(
            files.len() > 10,
            "sources not found under {}",
            dir.display()
        );
        let known = [
            "sse",
            "sse2",
            "sse3",
            "ssse3",
            "sse4.1",
            "sse4.2",
            "avx",
            "avx2",
            "fma",
            "f16c",
            "bmi1",
            "bmi2",
            "lzcnt",
            "popcnt",
            "avx512f",
            "avx512vl",
            "avx512dq",
            "avx512bw",
            "avx512cd",
            "avx512ifma",
            "avx512vbmi",
            "avx512vnni",
            "avx512bf16",
            "avx512fp16",
        ];
        let implied_by_avx2 = ["sse", "sse2", "sse3", "ssse3", "sse4.1", "sse4.2", "avx"];
        let mut lists = 0;
        for path in &files {
            let text = std::fs::read_to_string(path).unwrap();
            let own = path.file_name().unwrap() == "simd.rs";
            assert!(
                own || !text.contains("is_x86_feature_detected!"),
                "{} detects CPU features itself: ask crate::simd instead",
                path.display()
            );
            if own {
                continue;
            }
            // String literals made only of known feature names, comma-separated: the
            // `enable = "..."` lists, also those passed to macros.
            for lit in text.split('"').skip(1).step_by(2) {
                let feats: Vec<&str> = lit.split(',').collect();
                if lit.is_empty() || !feats.iter().all(|f| known.contains(f)) {
                    continue;
                }
                lists += 1;
                let level = if feats.iter().any(|f| f.starts_with("avx512")) {
                    Level::Avx512
                } else {
                    Level::Avx2Fma
                };
                for f in &feats {
                    assert!(
                        level.features().contains(f) || implied_by_avx2.contains(f),
                        "{}: \"{lit}\" enables {f}, which the {} level does not require",
                        path.display(),
                        level.name()
                    );
                }
            }
        }
        assert!(lists >= 10, "found only {lists} target_feature lists");
    }
}
