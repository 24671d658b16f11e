//! No intrinsic left as a call (#19 item 5). A kernel's vector operations are `std::arch`
//! intrinsics, which inline only into code compiled with their target features, i.e. into the
//! `simd::run` entry of their ISA and what is inlined into it. A helper that the compiler keeps
//! out of line (a closure called five times was one) is compiled without them, and every
//! intrinsic in it becomes a call of its own: 14 % of a mesh_light MIS pass once went to calls
//! of `_mm256_blendv_ps` and its kin. An out-of-line intrinsic is a function in the binary's
//! symbol table, so the `dibench` binary may hold none but the CPU detection's.

use std::process::Command;

/// The `core::core_arch` functions a binary defines (`nm` from binutils, which is installed
/// wherever Rust links), less those of CPU detection, which runs outside any kernel.
fn out_of_line_intrinsics(binary: &std::path::Path) -> Vec<String> {
    let out = Command::new("nm")
        .args(["-C", "--defined-only"])
        .arg(binary)
        .output()
        .unwrap_or_else(|e| panic!("running nm (binutils) on {}: {e}", binary.display()));
    assert!(
        out.status.success(),
        "nm {}: {}",
        binary.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let symbols = String::from_utf8_lossy(&out.stdout).into_owned();
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
