// Records the git commit the binary was built from, for run metadata.
fn main() {
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    let dirty = std::process::Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=no"])
        .output()
        .ok()
        .is_some_and(|o| !o.stdout.is_empty());
    println!(
        "cargo:rustc-env=DIBENCH_COMMIT={commit}{}",
        if dirty { "-dirty" } else { "" }
    );
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let rustc_version = std::process::Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=DIBENCH_RUSTC={rustc_version}");
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/index");
    if std::env::var_os("CARGO_FEATURE_EMBREE").is_some() {
        link_embree();
    }
}

/// Links the Embree 4.4 libraries that scripts/setup-embree.sh unpacks, with an rpath so
/// binaries, tests and benches run without LD_LIBRARY_PATH (libembree4 finds its tbb through
/// its own $ORIGIN rpath).
fn link_embree() {
    let dir = std::path::PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap())
        .join("third_party/embree/lib");
    println!("cargo:rerun-if-changed={}", dir.display());
    if !dir.join("libembree4.so").exists() {
        eprintln!(
            "error: the `embree` feature needs Embree 4.4 in {}; run scripts/setup-embree.sh first",
            dir.display()
        );
        panic!(
            "Embree libraries missing in {}: run scripts/setup-embree.sh",
            dir.display()
        );
    }
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
}
