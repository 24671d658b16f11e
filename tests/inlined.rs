//! No intrinsic left as a call (#19 item 5). A kernel's vector operations are `std::arch`
//! intrinsics, which inline only into code compiled with their target features, i.e. into the
//! `simd::run` entry of their ISA and what is inlined into it. A helper that the compiler keeps
//! out of line (a closure called five times was one) is compiled without them, and every
//! intrinsic in it becomes a call of its own: 14 % of a mesh_light MIS pass once went to calls
//! of `_mm256_blendv_ps` and its kin. An out-of-line intrinsic is a function in the binary's
//! symbol table, so the `dibench` binary may hold none but the CPU detection's.
//!
//! Nor a masked store the source did not ask for: LLVM folds `select(m, x, old).store(old)`
//! into `vmaskmovps`, which AMD's Zen 2 and Zen 3 issue at about one per 12 cycles (8 % of a
//! bunny `light` pass on a Zen 3), so the AVX2 path's stores hide their value from it
//! (`simd::avx2::opaque`).

use std::process::Command;

/// The output of binutils' `tool` (installed wherever Rust links) run with `args` on
/// `binary`; a failure to run it is a test failure naming the tool and the file.
fn binutils(tool: &str, args: &[&str], binary: &std::path::Path) -> String {
    let out = Command::new(tool)
        .args(args)
        .arg(binary)
        .output()
        .unwrap_or_else(|e| panic!("running {tool} (binutils) on {}: {e}", binary.display()));
    assert!(
        out.status.success(),
        "{tool} {}: {}",
        binary.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The `core::core_arch` functions a binary defines (`nm`), less those of CPU detection,
/// which runs outside any kernel.
fn out_of_line_intrinsics(binary: &std::path::Path) -> Vec<String> {
    let symbols = binutils("nm", &["-C", "--defined-only"], binary);
    assert!(
        symbols.lines().count() > 1000,
        "{}: no symbol table (stripped?)",
        binary.display()
    );
    symbols
        .lines()
        .filter_map(|l| l.splitn(3, ' ').nth(2))
        .filter(|name| name.starts_with("core::core_arch::"))
        .filter(|name| !name.contains("::xsave::_xgetbv") && !name.contains("::cpuid::"))
        .map(str::to_string)
        .collect()
}

#[test]
fn no_intrinsic_is_left_as_a_call() {
    let found = out_of_line_intrinsics(env!("CARGO_BIN_EXE_dibench").as_ref());
    assert!(
        found.is_empty(),
        "intrinsics compiled out of line, i.e. called from code without their target \
         features (find the callers with `objdump -d -C`): {found:#?}"
    );
}

/// Control: an intrinsic used outside its target feature, as an out-of-line closure in a
/// kernel would, leaves a function in this test's own binary, and the check finds it.
#[cfg(target_arch = "x86_64")]
#[test]
fn an_intrinsic_outside_its_target_feature_is_found() {
    use std::arch::x86_64::{__m256i, _mm256_and_si256};
    #[inline(never)]
    fn and_without_avx2(a: __m256i, b: __m256i) -> __m256i {
        // SAFETY: never called; only compiled, so that the intrinsic is kept out of line.
        unsafe { _mm256_and_si256(a, b) }
    }
    std::hint::black_box(and_without_avx2 as fn(__m256i, __m256i) -> __m256i);
    let found = out_of_line_intrinsics(&std::env::current_exe().unwrap());
    assert!(
        found.iter().any(|s| s.ends_with("_mm256_and_si256")),
        "not found: {found:#?}"
    );
}

/// The masked stores (`vmaskmovps`/`vmaskmovpd` with a memory destination, as `objdump -d`
/// prints them in AT&T order, destination last) in the functions of `binary` whose demangled
/// names mention `path` (a crate's, so that a dependency's own masked stores, as in
/// ab_glyph's rasterizer, are not counted), each as "function: instruction".
#[cfg(target_arch = "x86_64")]
fn masked_stores(binary: &std::path::Path, path: &str) -> Vec<String> {
    let text = binutils("objdump", &["-d", "-C", "--no-show-raw-insn"], binary);
    let mut function = "";
    let (mut instructions, mut found) = (0usize, Vec::new());
    for line in text.lines() {
        if let Some(name) = line.strip_suffix(">:").and_then(|l| l.split_once(" <")) {
            function = name.1;
        } else if let Some((_, ins)) = line.split_once(":\t") {
            instructions += 1;
            let ins = ins.trim();
            if function.contains(path) && ins.starts_with("vmaskmovp") && ins.ends_with(')') {
                found.push(format!("{function}: {ins}"));
            }
        }
    }
    assert!(
        instructions > 10_000,
        "{}: no instructions read from objdump",
        binary.display()
    );
    found
}

#[cfg(target_arch = "x86_64")]
#[test]
fn no_masked_store_is_made_of_a_select_and_a_store() {
    let found = masked_stores(env!("CARGO_BIN_EXE_dibench").as_ref(), "dibench::");
    assert!(
        found.is_empty(),
        "masked stores in dibench's code (a store of a select of the same place's old value, \
         folded by LLVM; store through simd::avx2's store, which hides the value): {found:#?}"
    );
}

/// Control: the pattern, a blend of a place's old value stored back to it, written with the
/// intrinsics and no barrier, becomes a masked store in this test's binary, and the check
/// finds it; a plain store beside it is not reported.
#[cfg(target_arch = "x86_64")]
#[test]
fn a_select_stored_back_is_found_as_a_masked_store() {
    use std::arch::x86_64::*;
    #[target_feature(enable = "avx")]
    #[inline(never)]
    unsafe fn keep_lanes_unhidden(m: __m256, x: __m256, p: *mut f32) {
        // SAFETY: never called; only compiled.
        unsafe { _mm256_storeu_ps(p, _mm256_blendv_ps(_mm256_loadu_ps(p), x, m)) }
    }
    #[target_feature(enable = "avx")]
    #[inline(never)]
    unsafe fn store_plainly(x: __m256, p: *mut f32) {
        // SAFETY: never called; only compiled.
        unsafe { _mm256_storeu_ps(p, x) }
    }
    std::hint::black_box(keep_lanes_unhidden as unsafe fn(__m256, __m256, *mut f32));
    std::hint::black_box(store_plainly as unsafe fn(__m256, *mut f32));
    let found = masked_stores(&std::env::current_exe().unwrap(), "inlined::");
    assert!(
        found.iter().any(|s| s.contains("keep_lanes_unhidden")),
        "not found: {found:#?}"
    );
    assert!(
        !found.iter().any(|s| s.contains("store_plainly")),
        "a plain store reported: {found:#?}"
    );
}
