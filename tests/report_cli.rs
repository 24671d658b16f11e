//! `dibench report` through the CLI: a real compare run with two integrands (direct and AO,
//! so two references) becomes one self-contained report.html; bad run directories are errors
//! naming what is wrong, with exit status 1 and no panic.

mod common;
use common::{TINY_WITH_AO as SCENE, dibench};

use std::path::{Path, PathBuf};

fn compare(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("tiny.toml"), SCENE).unwrap();
    let (code, _, stderr) = dibench(
        &[
            "compare",
            "tiny.toml",
            "--runs",
            "2",
            "--time",
            "0.03",
            "--reference-spp",
            "16",
            "--strategies",
            "light,cosine,ao-cosine",
            "--threads",
            "1",
            "--out",
            "out",
        ],
        dir,
    );
    assert_eq!(code, 0, "{stderr}");
    std::fs::read_dir(dir.join("out/tiny"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| !p.ends_with("reference"))
        .unwrap()
}

#[test]
fn report_writes_one_page_with_every_image_and_both_references() {
    let dir = tempfile::tempdir().unwrap();
    let run = compare(dir.path());
    // compare wrote the page; the subcommand writes it anew.
    let by_compare = std::fs::read_to_string(run.join("report.html")).unwrap();
    std::fs::remove_file(run.join("report.html")).unwrap();
    let (code, stdout, stderr) = dibench(&["report", run.to_str().unwrap()], dir.path());
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.trim().ends_with("report.html"), "{stdout}");
    let html = std::fs::read_to_string(run.join("report.html")).unwrap();
    let start = "<script type=\"application/json\" id=\"dibench-data\">";
    let a = html.find(start).unwrap() + start.len();
    let b = a + html[a..].find("</script>").unwrap();
    let data: serde_json::Value = serde_json::from_str(&html[a..b]).unwrap();
    let names: Vec<&str> = data["images"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    for n in [
        "reference:direct",
        "reference:ao",
        "light",
        "cosine",
        "ao-cosine",
    ] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
    assert_eq!(
        html, by_compare,
        "the subcommand's page differs from compare's"
    );
    // One pixel block per image, variance, FLIP map and reference: 3 strategies × 3 + 2
    // references.
    assert_eq!(
        html.matches("type=\"application/octet-stream\"").count(),
        11
    );
    // Self-contained: no URL the browser would fetch.
    for needle in ["http://", "https://", "src=\"", "href=\"http"] {
        let hits: Vec<usize> = html.match_indices(needle).map(|(i, _)| i).collect();
        // The only http:// is the SVG namespace string in the script.
        let allowed = hits
            .iter()
            .all(|&i| html[i..].starts_with("http://www.w3.org/2000/svg"));
        assert!(allowed, "{needle} in the page");
    }
}

#[test]
fn bad_run_directories_are_errors_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, stderr) = dibench(&["report", "no_such_dir"], dir.path());
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("no_such_dir"), "{stderr}");
    let (code, _, stderr) = dibench(&["report", "."], dir.path());
    assert_eq!(code, 1);
    assert!(stderr.contains("run.json"), "{stderr}");
    let run = compare(dir.path());
    std::fs::remove_file(run.join("report.html")).unwrap();
    std::fs::write(run.join("summary.csv"), "garbage\n").unwrap();
    let (code, _, stderr) = dibench(&["report", run.to_str().unwrap()], dir.path());
    assert_eq!(code, 1);
    assert!(stderr.contains("summary.csv"), "{stderr}");
    assert!(!run.join("report.html").exists());
}
