use super::*;
use crate::film::Image;
use crate::harness::reference::{ReferenceMeta, save, store};
use crate::output::{read_exr, write_exr};

const SUMMARY: &str = "scene,integrand,strategy,runs,rmse_mean,vs_best,sampler\n\
    t,direct,light,2,0.25,best,independent\n\
    t,direct,bsdf,2,0.5,worse,independent\n";
const RESULTS: &str = "scene,strategy,integrand,backend,threads,run,seed,checkpoint,time_s,spp,rmse,relmse,sampler\n\
    t,light,direct,packet,1,0,1,7,0.1,8,0.25,0.1,independent\n\
    t,bsdf,direct,packet,1,0,1,7,0.1,8,0.5,0.2,independent\n";

fn image(w: u32, h: u32, seed: f64) -> Image {
    Image {
        width: w,
        height: h,
        pixels: (0..w * h)
            .map(|i| {
                let v = i as f64 * 0.37 + seed;
                // f32-exact values, some tiny, some large, one negative.
                [
                    v.fract() as f32 as f64,
                    (v * 1e-4) as f32 as f64,
                    (-v * 3.5) as f32 as f64,
                ]
            })
            .collect(),
    }
}

/// `<root>/t/run` with run.json, summary.csv, results.csv, two strategies' images and
/// variances, and the `direct` reference stored in `<root>/t/reference`.
fn run_dir(root: &Path, w: u32, h: u32) -> PathBuf {
    let run = root.join("t").join("run");
    std::fs::create_dir_all(&run).unwrap();
    std::fs::write(
        run.join("run.json"),
        serde_json::to_string(
            &json!({"scene": "t", "width": w, "height": h, "status": "complete",
            "reference_spp": [["direct", 64]]}),
        )
        .unwrap(),
    )
    .unwrap();
    std::fs::write(run.join("summary.csv"), SUMMARY).unwrap();
    std::fs::write(run.join("results.csv"), RESULTS).unwrap();
    for (k, s) in ["light", "bsdf"].iter().enumerate() {
        write_exr(&run.join(format!("{s}.exr")), &image(w, h, k as f64 + 0.5)).unwrap();
        write_exr(
            &run.join(format!("{s}.variance.exr")),
            &image(w, h, k as f64 + 7.0),
        )
        .unwrap();
    }
    let st = store(root, "t").unwrap();
    let unit = st.lock("direct").unwrap();
    let meta = ReferenceMeta {
        scene: "t".into(),
        integrand: "direct".into(),
        scene_hash: "h".into(),
        width: w,
        height: h,
        spp: 64,
        seed: 1,
        strategy: "light".into(),
        backend: "packet".into(),
        threads: 1,
        wall_time_s: 0.1,
        noise_floor_rmse: Some(0.01),
        dibench_version: "0".into(),
        commit: "c".into(),
        cpu: None,
    };
    save(&unit, &image(w, h, 0.0), &image(w, h, 3.0), &meta).unwrap();
    run
}

/// Standard base64 decoding, written independently of the encoder.
fn unbase64(s: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut out = Vec::new();
    for q in s.as_bytes().chunks(4) {
        let pad = q.iter().filter(|&&c| c == b'=').count();
        let n = q
            .iter()
            .map(|&c| if c == b'=' { 0 } else { value(c) as u32 })
            .fold(0u32, |n, v| n << 6 | v);
        out.extend_from_slice(&n.to_be_bytes()[1..4 - pad]);
    }
    out
}

/// The page's JSON block, and its pixel blocks decoded (little-endian f32), by id.
fn parse_page(html: &str) -> (Value, std::collections::HashMap<String, Vec<f32>>) {
    let start = "<script type=\"application/json\" id=\"dibench-data\">";
    let a = html.find(start).expect("no data block") + start.len();
    let b = a + html[a..].find("</script>").unwrap();
    let data: Value = serde_json::from_str(&html[a..b]).unwrap();
    let mut blocks = std::collections::HashMap::new();
    let tag = "<script type=\"application/octet-stream\" id=\"";
    let mut rest = html;
    while let Some(i) = rest.find(tag) {
        rest = &rest[i + tag.len()..];
        let id = &rest[..rest.find('"').unwrap()];
        let body = &rest[rest.find('>').unwrap() + 1..rest.find("</script>").unwrap()];
        let floats = unbase64(body)
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        blocks.insert(id.to_string(), floats);
    }
    (data, blocks)
}

fn f32s(img: &Image) -> Vec<f32> {
    img.pixels.iter().flatten().map(|&v| v as f32).collect()
}

#[test]
fn base64_matches_the_rfc_4648_test_vectors() {
    // RFC 4648 §10; a wrong padding or bit order would garble every embedded image.
    for (plain, coded) in [
        ("", ""),
        ("f", "Zg=="),
        ("fo", "Zm8="),
        ("foo", "Zm9v"),
        ("foob", "Zm9vYg=="),
        ("fooba", "Zm9vYmE="),
        ("foobar", "Zm9vYmFy"),
    ] {
        assert_eq!(base64(plain.as_bytes()), coded, "{plain:?}");
        assert_eq!(unbase64(coded), plain.as_bytes());
    }
    let all: Vec<u8> = (0..=255).collect();
    assert_eq!(unbase64(&base64(&all)), all);
}

/// What the page embeds decodes to the EXRs' own f32 values, bit for bit: the images and the
/// reference as RGB, the variance as the mean of its RGB.
#[test]
fn embedded_pixels_round_trip_to_the_exr_values() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 7, 5);
    let html = build_report(&run).unwrap();
    let (data, blocks) = parse_page(&html);
    assert_eq!(data["format"], FORMAT);
    assert_eq!(
        (data["width"].as_u64(), data["height"].as_u64()),
        (Some(7), Some(5))
    );
    let images = data["images"].as_array().unwrap();
    let names: Vec<&str> = images.iter().map(|i| i["name"].as_str().unwrap()).collect();
    // The reference first, then the strategies in summary.csv's order.
    assert_eq!(names, ["reference", "light", "bsdf"]);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for im in images {
        let name = im["name"].as_str().unwrap();
        let px = &blocks[im["pixels"].as_str().unwrap()];
        let exr = if name == "reference" {
            // The file name is relative to the run directory.
            read_exr(&run.join(im["file"].as_str().unwrap())).unwrap()
        } else {
            read_exr(&run.join(format!("{name}.exr"))).unwrap()
        };
        assert_eq!(bits(px), bits(&f32s(&exr)), "{name}");
        if name != "reference" {
            let var = read_exr(&run.join(format!("{name}.variance.exr"))).unwrap();
            let mean: Vec<f32> = var
                .pixels
                .iter()
                .map(|p| ((p[0] + p[1] + p[2]) / 3.0) as f32)
                .collect();
            assert_eq!(bits(&blocks[im["variance"].as_str().unwrap()]), bits(&mean));
            assert!(im["flip"].is_null(), "no FLIP file, yet {im}");
        }
    }
    assert_eq!(data["summary"]["rows"].as_array().unwrap().len(), 2);
    assert_eq!(data["eps"], crate::metrics::EPS);
    assert!(!html.contains("{{"), "a template marker is left");
    assert!(
        html.contains("window.dibenchReport"),
        "the script is missing"
    );
}

#[test]
fn write_report_leaves_report_html_and_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let path = write_report(&run).unwrap();
    assert_eq!(path, run.join(REPORT));
    let names: Vec<String> = std::fs::read_dir(&run)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.iter().all(|n| !crate::output::is_temp_name(n)),
        "{names:?}"
    );
    assert!(
        std::fs::read_to_string(&path)
            .unwrap()
            .starts_with("<!DOCTYPE html>")
    );
}

fn err(run: &Path) -> String {
    build_report(run).unwrap_err().to_string()
}

#[test]
fn a_directory_without_run_json_is_not_a_run_dir() {
    let dir = tempfile::tempdir().unwrap();
    let msg = err(dir.path());
    assert!(
        msg.contains("not a compare run directory") && msg.contains("run.json"),
        "{msg}"
    );
    let msg = err(&dir.path().join("absent"));
    assert!(
        msg.contains("absent") && msg.contains("not a directory"),
        "{msg}"
    );
}

#[test]
fn missing_or_corrupt_summary_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let summary = run.join("summary.csv");
    std::fs::remove_file(&summary).unwrap();
    let msg = err(&run);
    assert!(msg.contains("summary.csv"), "{msg}");
    for (content, says) in [
        ("", "no `strategy` column"),
        ("scene,integrand,strategy\n", "no rows"),
        ("scene,strategy\nt,light\n", "no `integrand` column"),
        ("scene,integrand,strategy\nt,direct\n", "not a readable CSV"),
        (
            "scene,integrand,strategy\nt,direct,../../etc\n",
            "not a strategy name",
        ),
    ] {
        std::fs::write(&summary, content).unwrap();
        let msg = err(&run);
        assert!(
            msg.contains("summary.csv") && msg.contains(says),
            "{content:?}: {msg}"
        );
    }
    std::fs::write(&summary, [0xff, 0xfe, b'\n', 0x80]).unwrap();
    assert!(err(&run).contains("summary.csv"));
}

#[test]
fn an_image_of_another_size_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    write_exr(&run.join("bsdf.exr"), &image(3, 4, 0.0)).unwrap();
    let msg = err(&run);
    assert!(
        msg.contains("bsdf.exr") && msg.contains("3×4") && msg.contains("4×3"),
        "{msg}"
    );
    // The variance too.
    write_exr(&run.join("bsdf.exr"), &image(4, 3, 0.0)).unwrap();
    write_exr(&run.join("light.variance.exr"), &image(5, 3, 0.0)).unwrap();
    let msg = err(&run);
    assert!(
        msg.contains("light.variance.exr") && msg.contains("5×3"),
        "{msg}"
    );
}

/// A header claiming 2^29 rows is refused from the header, before its pixels are decoded (a
/// decode would first allocate for them).
#[test]
fn sizes_are_checked_from_the_header_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 4);
    let path = run.join("light.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    let at = bytes.windows(10).position(|w| w == b"dataWindow").unwrap();
    let y_max = at + b"dataWindow\0box2i\0".len() + 4 + 12;
    bytes[y_max..y_max + 4].copy_from_slice(&(1i32 << 29).to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let msg = err(&run);
    assert!(
        msg.contains("light.exr") && msg.contains("4×536870913"),
        "{msg}"
    );
}

#[test]
fn pixel_data_over_the_limit_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 8, 8);
    // Reference 768 B, light 768 B + 256 B of variance: the bsdf image passes 2000 B.
    let msg = build(&run, 2000).unwrap_err().to_string();
    assert!(
        msg.contains("bsdf.exr") && msg.contains("too large to embed"),
        "{msg}"
    );
    assert!(build(&run, 4096).is_ok());
}

#[test]
fn a_missing_reference_is_an_error_naming_its_manifest() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    std::fs::remove_file(dir.path().join("t/reference/direct.json")).unwrap();
    let msg = err(&run);
    assert!(
        msg.contains("reference/direct.json") && msg.contains("no stored direct reference"),
        "{msg}"
    );
}

/// A damaged reference file is caught by the store's hash, not shown as a wrong image.
#[test]
fn a_damaged_reference_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let refdir = dir.path().join("t/reference");
    let exr = std::fs::read_dir(&refdir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.ends_with(".exr") && !n.ends_with(".variance.exr")
        })
        .unwrap();
    let mut bytes = std::fs::read(&exr).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x55;
    std::fs::write(&exr, bytes).unwrap();
    let msg = err(&run);
    assert!(
        msg.contains(&exr.file_name().unwrap().to_string_lossy().to_string()),
        "{msg}"
    );
}

fn write_channels(path: &Path, names: &[&str], w: usize, h: usize) {
    use exr::prelude::*;
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            AnyChannel::new(
                *n,
                FlatSamples::F32((0..w * h).map(|i| i as f32 * 0.125 + k as f32).collect()),
            )
        })
        .collect();
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels),
    );
    exr::image::Image::from_layer(layer)
        .write()
        .to_file(path)
        .unwrap();
}

/// FLIP maps: one channel of any name, or the R of several; other layouts are refused.
#[test]
fn flip_maps_take_the_only_channel_or_r() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let want: Vec<f32> = (0..12).map(|i| i as f32 * 0.125).collect();
    for names in [&["Y"][..], &["B", "G", "R"][..]] {
        let flip = run.join("light.flip.exr");
        write_channels(&flip, names, 4, 3);
        let (data, blocks) = parse_page(&build_report(&run).unwrap());
        let light = &data["images"][1];
        assert_eq!(light["name"], "light");
        // R is channel 2 of B, G, R: its values are offset by 2.
        let offset = if names.len() == 1 { 0.0 } else { 2.0 };
        let got = &blocks[light["flip"].as_str().unwrap()];
        let expected: Vec<f32> = want.iter().map(|v| v + offset).collect();
        assert_eq!(got, &expected, "{names:?}");
        assert!(data["images"][2]["flip"].is_null());
    }
    write_channels(&run.join("light.flip.exr"), &["X", "Z"], 4, 3);
    let msg = err(&run);
    assert!(
        msg.contains("light.flip.exr") && msg.contains("X, Z"),
        "{msg}"
    );
    write_channels(&run.join("light.flip.exr"), &["Y"], 3, 3);
    assert!(err(&run).contains("light.flip.exr"));
}

/// Text from the run (here run.json's error) cannot end the data block early.
#[test]
fn run_text_cannot_close_the_script_element() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let evil = "</script><script>alert(1)</script><!--";
    std::fs::write(
        run.join("run.json"),
        json!({"scene": "t<b>", "width": 4, "height": 3, "status": "failed", "error": evil})
            .to_string(),
    )
    .unwrap();
    let html = build_report(&run).unwrap();
    assert!(!html.contains(evil));
    assert!(!html.contains("<b>"), "the title is not escaped");
    let (data, _) = parse_page(&html);
    assert_eq!(
        data["run"]["error"], evil,
        "the text must survive the escaping"
    );
    assert!(data["notes"][0].as_str().unwrap().contains("failed"));
}

/// A reference replaced after the run (another spp than run.json names) is said on the page.
#[test]
fn a_replaced_reference_is_noted() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    let mut meta: Value =
        serde_json::from_slice(&std::fs::read(run.join("run.json")).unwrap()).unwrap();
    meta["reference_spp"] = json!([["direct", 1024]]);
    std::fs::write(run.join("run.json"), meta.to_string()).unwrap();
    let (data, _) = parse_page(&build_report(&run).unwrap());
    let notes = data["notes"].to_string();
    assert!(
        notes.contains("64 spp") && notes.contains("1024 spp"),
        "{notes}"
    );
}

/// Every file the page needs is named when it is missing: results.csv, a strategy's image.
#[test]
fn a_missing_results_csv_or_image_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let run = run_dir(dir.path(), 4, 3);
    std::fs::remove_file(run.join("bsdf.exr")).unwrap();
    let msg = err(&run);
    assert!(msg.contains("bsdf.exr"), "{msg}");
    std::fs::remove_file(run.join("results.csv")).unwrap();
    let msg = err(&run);
    assert!(msg.contains("results.csv"), "{msg}");
    // A variance or FLIP file is optional: without them the page still builds.
    let run = run_dir(&dir.path().join("b"), 4, 3);
    std::fs::remove_file(run.join("light.variance.exr")).unwrap();
    let (data, _) = parse_page(&build_report(&run).unwrap());
    assert!(data["images"][1]["variance"].is_null());
    assert!(data["images"][2]["variance"].is_string());
}
