//! `report.html`: one self-contained page of a compare run directory, for looking at the
//! results in a browser (works from `file://`, loads nothing from the network): the sortable
//! summary table, the convergence plot drawn from results.csv, a flip-book viewer of the
//! reference and every strategy's equal-time image (exposure, zoom to single pixels, pan,
//! pixel readout), per-strategy error maps (relMSE, variance of the mean, FLIP when a
//! `<stem>.flip.exr` is there) and statistics of a selected region. See docs/report.md.
//!
//! The page is the template `assets/report/report.html` with our own CSS and JavaScript
//! (`assets/report/report.{css,js}`) and the run's data inlined:
//! - a JSON block (`<script type="application/json" id="dibench-data">`): run.json, the rows
//!   of summary.csv and results.csv as text, and per image its name, kind, integrand, size and
//!   the ids of its pixel blocks;
//! - one `<script type="application/octet-stream">` block per pixel array: little-endian f32,
//!   base64 (RFC 4648, padded), row-major from the top-left pixel; 3 channels interleaved
//!   (RGB) for images and references, 1 channel for the variance (mean of RGB) and FLIP.
//!
//! The f32 values are the EXRs' own, so the page shows exactly what the files hold. The raw
//! pixel data is limited to [`MAX_EMBED_BYTES`] in all; sizes are read from each EXR header
//! and checked (against the run's size and the limit) before its pixels are decoded.

use crate::error::{Error, Result};
use crate::harness::compare::image_stem;
use crate::output::decode_exr;
use serde_json::{Value, json};
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// The file written into the run directory.
pub const REPORT: &str = "report.html";

/// The most raw pixel data (f32 bytes, before base64's 4/3) a report embeds: 96 MiB, about
/// 128 MiB of HTML, which a browser still opens in a few seconds. A 512×512 run with 20
/// strategies needs about 25 MiB.
pub const MAX_EMBED_BYTES: u64 = 96 << 20;

/// The version of the embedded data layout (the JSON block's `format`).
pub const FORMAT: &str = "dibench-report/1";

static TEMPLATE: &str = include_str!("../../assets/report/report.html");
static CSS: &str = include_str!("../../assets/report/report.css");
static JS: &str = include_str!("../../assets/report/report.js");

/// A CSV file read as text: its header and rows, every row as long as the header.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Reads the CSV `path`; an error names it when it is missing, not CSV, has rows of
    /// another length than its header, no rows, or lacks one of `required` columns.
    pub fn read(path: &Path, required: &[&str]) -> Result<Table> {
        let bytes = crate::bounded::read_file(path, 4)?;
        let bad = |message: String| Error::Parse {
            path: path.into(),
            message,
        };
        let mut reader = csv::ReaderBuilder::new().from_reader(&bytes[..]);
        let columns: Vec<String> = reader
            .headers()
            .map_err(|e| bad(format!("not a readable CSV file: {e}")))?
            .iter()
            .map(str::to_string)
            .collect();
        for r in required {
            if !columns.iter().any(|c| c == r) {
                return Err(bad(format!(
                    "no `{r}` column (columns: {}); not written by `dibench compare`?",
                    columns.join(", ")
                )));
            }
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| bad(format!("not a readable CSV file: {e}")))?;
            rows.push(record.iter().map(str::to_string).collect());
        }
        if rows.is_empty() {
            return Err(bad("no rows".into()));
        }
        Ok(Table { columns, rows })
    }

    fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The value of column `name` in row `row`, or `default` where there is no such column.
    fn get<'a>(&'a self, row: &'a [String], name: &str, default: &'a str) -> &'a str {
        self.column(name).map_or(default, |i| row[i].as_str())
    }

    fn to_json(&self) -> Value {
        json!({ "columns": self.columns, "rows": self.rows })
    }
}

/// A decoded EXR: `channels` interleaved f32 values per pixel, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Pixels {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub data: Vec<f32>,
}

/// What the pixel data of a report adds up to, checked before each file is decoded.
struct Budget {
    used: u64,
    limit: u64,
    /// The run's image size: run.json's, else the first file's.
    size: Option<(usize, usize)>,
}

impl Budget {
    /// Checks the EXR `bytes` (read from `path`) by its header: its size must be the run's
    /// (the first file sets it when run.json gives none), and `channels` f32 per pixel must fit
    /// in what is left of [`MAX_EMBED_BYTES`] and in memory.
    fn admit(&mut self, bytes: &[u8], path: &Path, channels: u64) -> Result<()> {
        let meta =
            exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| {
                Error::Parse {
                    path: path.into(),
                    message: format!("not a readable EXR image: {e}"),
                }
            })?;
        let Some(h) = meta.headers.first() else {
            return Err(Error::Parse {
                path: path.into(),
                message: "an EXR without a layer".into(),
            });
        };
        let size = (h.layer_size.width(), h.layer_size.height());
        match self.size {
            Some(want) if want != size => {
                return Err(Error::Parse {
                    path: path.into(),
                    message: format!(
                        "{}×{} pixels, but the run's images are {}×{}",
                        size.0, size.1, want.0, want.1
                    ),
                });
            }
            _ => self.size = Some(size),
        }
        let need = crate::bounded::bytes(size.0 as u64 * size.1 as u64, 4 * channels);
        let total = self.used.saturating_add(need);
        if total > self.limit {
            return Err(Error::Output {
                path: path.into(),
                message: format!(
                    "too large to embed in a report: with this {}×{} image the pixel data \
                     comes to {}, over the limit of {} (report::MAX_EMBED_BYTES)",
                    size.0,
                    size.1,
                    crate::bounded::human_bytes(total),
                    crate::bounded::human_bytes(self.limit)
                ),
            });
        }
        // The decoded f32 values, their bytes in base64, and the decoder's own copy.
        crate::bounded::check_memory(
            || format!("{}: a {}×{} image", path.display(), size.0, size.1),
            crate::bounded::bytes(need, 4),
        )?;
        self.used = total;
        Ok(())
    }

    /// Checks `px`, decoded from `path`, against the size its header gave (a file with several
    /// layers may decode another one).
    fn decoded(&self, px: Pixels, path: &Path) -> Result<Pixels> {
        match self.size {
            Some(want) if want != (px.width, px.height) => Err(Error::Parse {
                path: path.into(),
                message: format!(
                    "decodes to {}×{} pixels, but the run's images are {}×{}",
                    px.width, px.height, want.0, want.1
                ),
            }),
            _ => Ok(px),
        }
    }

    /// [`Budget::admit`], then the file decoded by `decode` and checked by [`Budget::decoded`].
    fn load(
        &mut self,
        bytes: &[u8],
        path: &Path,
        channels: u64,
        decode: fn(&[u8], &Path) -> Result<Pixels>,
    ) -> Result<Pixels> {
        self.admit(bytes, path, channels)?;
        let px = decode(bytes, path)?;
        self.decoded(px, path)
    }
}

/// Decodes the RGB(A) EXR `bytes` (from `path`) as 3-channel f32.
fn rgb(bytes: &[u8], path: &Path) -> Result<Pixels> {
    let (width, height, px) = decode_exr(bytes, path, |r, g, b| [r, g, b])?;
    Ok(Pixels {
        width,
        height,
        channels: 3,
        data: px.into_iter().flatten().collect(),
    })
}

/// Decodes a FLIP map: the only channel of a one-channel EXR, or the `R` channel of one with
/// several (an RGB(A) FLIP image carries the value in R).
pub fn read_flip(bytes: &[u8], path: &Path) -> Result<Pixels> {
    use exr::prelude::ReadChannels as _;
    use exr::prelude::ReadLayers as _;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| Error::Parse {
            path: path.into(),
            message: format!("not a readable EXR image: {e}"),
        })?;
    let layer = image.layer_data;
    let list = &layer.channel_data.list;
    let channel = match list.iter().find(|c| c.name.eq("R")) {
        Some(c) => c,
        None if list.len() == 1 => &list[0],
        None => {
            let names: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
            return Err(Error::Parse {
                path: path.into(),
                message: format!(
                    "a FLIP map needs one channel, or the value in R; this one has {}",
                    names.join(", ")
                ),
            });
        }
    };
    Ok(Pixels {
        width: layer.size.width(),
        height: layer.size.height(),
        channels: 1,
        data: channel.sample_data.values_as_f32().collect(),
    })
}

/// The per-pixel mean of the three channels of an RGB image.
fn mean_of_rgb(p: &Pixels) -> Pixels {
    Pixels {
        width: p.width,
        height: p.height,
        channels: 1,
        data: p
            .data
            .chunks_exact(3)
            .map(|c| ((c[0] as f64 + c[1] as f64 + c[2] as f64) / 3.0) as f32)
            .collect(),
    }
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard base64 with padding (RFC 4648 §4).
pub fn base64(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The embedded encoding of a pixel array: little-endian f32, base64.
pub fn encode_f32(values: &[f32]) -> String {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    base64(&bytes)
}

/// The pixel arrays of the page, by block id, in the order they are written.
struct Blocks(Vec<(String, String)>);

impl Blocks {
    fn add(&mut self, p: &Pixels) -> String {
        let id = format!("px{}", self.0.len());
        self.0.push((id.clone(), encode_f32(&p.data)));
        id
    }
}

/// A name that becomes part of a file name in the run directory, and nothing outside it.
fn file_name_part(table: &Path, what: &str, name: &str) -> Result<()> {
    if name.is_empty() || Path::new(name).file_name() != Some(name.as_ref()) {
        return Err(Error::Parse {
            path: table.into(),
            message: format!("`{name}` is not a {what} name"),
        });
    }
    Ok(())
}

/// Reads the run directory and builds the page (see the module comment); nothing is written.
pub fn build_report(run_dir: &Path) -> Result<String> {
    build(run_dir, MAX_EMBED_BYTES)
}

/// [`build_report`] with `limit` bytes of pixel data at most.
fn build(run_dir: &Path, limit: u64) -> Result<String> {
    let meta_path = run_dir.join("run.json");
    if !run_dir.is_dir() {
        return Err(Error::Usage(format!(
            "{}: not a directory; give a run directory written by `dibench compare` \
             (<out>/<scene>/<run id>)",
            run_dir.display()
        )));
    }
    if !meta_path.exists() {
        return Err(Error::Usage(format!(
            "{}: not a compare run directory (no run.json)",
            run_dir.display()
        )));
    }
    let run: Value =
        serde_json::from_slice(&crate::bounded::read_file(&meta_path, 8)?).map_err(|e| {
            Error::Parse {
                path: meta_path.clone(),
                message: format!("not valid JSON: {e}"),
            }
        })?;
    if !run.is_object() {
        return Err(Error::Parse {
            path: meta_path,
            message: "not a JSON object".into(),
        });
    }
    let summary_path = run_dir.join("summary.csv");
    let summary = Table::read(&summary_path, &["strategy", "integrand"])?;
    let results_path = run_dir.join("results.csv");
    let results = Table::read(
        &results_path,
        &[
            "strategy",
            "integrand",
            "run",
            "checkpoint",
            "time_s",
            "rmse",
        ],
    )?;
    let default_sampler = crate::sampling::GENERATORS[0].name();
    let mut notes: Vec<String> = Vec::new();
    match run.get("status").and_then(Value::as_str) {
        Some("complete") => {}
        Some(s) => notes.push(format!(
            "run.json says the run is `{s}`: the report shows what it holds"
        )),
        None => notes.push("run.json has no status".into()),
    }

    // The images: one per (strategy, sampler) of summary.csv, in its order (ranked).
    struct Entry {
        strategy: String,
        sampler: String,
        integrand: String,
    }
    let mut entries: Vec<Entry> = Vec::new();
    for row in &summary.rows {
        let strategy = summary.get(row, "strategy", "").to_string();
        let sampler = summary.get(row, "sampler", default_sampler).to_string();
        let integrand = summary.get(row, "integrand", "").to_string();
        file_name_part(&summary_path, "strategy", &strategy)?;
        file_name_part(&summary_path, "sampler", &sampler)?;
        file_name_part(&summary_path, "integrand", &integrand)?;
        if !entries
            .iter()
            .any(|e| e.strategy == strategy && e.sampler == sampler)
        {
            entries.push(Entry {
                strategy,
                sampler,
                integrand,
            });
        }
    }
    let mut integrands: Vec<String> = Vec::new();
    for e in &entries {
        if !integrands.contains(&e.integrand) {
            integrands.push(e.integrand.clone());
        }
    }

    let size = match (
        run.get("width").and_then(Value::as_u64),
        run.get("height").and_then(Value::as_u64),
    ) {
        (Some(w), Some(h)) => Some((w as usize, h as usize)),
        _ => None,
    };
    let mut budget = Budget {
        used: 0,
        limit,
        size,
    };
    let mut blocks = Blocks(Vec::new());
    let mut images: Vec<Value> = Vec::new();

    // References: <out>/<scene>/reference/<integrand>.json, verified through the store.
    let scene_dir = run_dir
        .canonicalize()
        .map_err(|e| Error::io(run_dir, e))?
        .parent()
        .map(Path::to_path_buf)
        .ok_or_else(|| Error::Usage(format!("{}: has no parent directory", run_dir.display())))?;
    let ref_dir = crate::harness::reference::reference_dir(
        scene_dir.parent().unwrap_or(Path::new("/")),
        &scene_dir.file_name().unwrap_or_default().to_string_lossy(),
    );
    let run_spp = |integrand: &str| -> Option<u64> {
        run.get("reference_spp")?
            .as_array()?
            .iter()
            .find(|p| p.get(0).and_then(Value::as_str) == Some(integrand))?
            .get(1)?
            .as_u64()
    };
    for integrand in &integrands {
        let manifest = ref_dir.join(format!("{integrand}.json"));
        if !manifest.is_file() {
            return Err(Error::Parse {
                path: manifest,
                message: format!(
                    "no stored {integrand} reference: the report compares each strategy with \
                     the reference of its integrand in <out>/<scene>/reference/, beside the \
                     run directory"
                ),
            });
        }
        let store = crate::output::store::Store::open(&ref_dir)?;
        let unit = store.lock_shared(integrand)?;
        let Some(stored) = unit.read::<Value>()? else {
            return Err(Error::Parse {
                path: manifest,
                message: "a reference without a file list (written by an older dibench): \
                          render it again with `dibench reference`"
                    .into(),
            });
        };
        let (path, bytes) = stored.file("image")?;
        let px = budget.load(bytes, path, 3, rgb)?;
        let spp = stored.meta.get("spp").and_then(Value::as_u64);
        if let (Some(now), Some(then)) = (spp, run_spp(integrand))
            && now != then
        {
            notes.push(format!(
                "the stored {integrand} reference has {now} spp, but the run measured against \
                 one of {then} spp (replaced since): the page's errors are against the stored \
                 one, summary.csv's against the run's"
            ));
        }
        let name = if integrands.len() == 1 {
            "reference".to_string()
        } else {
            format!("reference:{integrand}")
        };
        images.push(json!({
            "name": name,
            "kind": "reference",
            "integrand": integrand,
            // Relative to the run directory, so the page does not depend on how its
            // directory was named on the command line.
            "file": format!(
                "../reference/{}",
                path.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned())
            ),
            "spp": spp,
            "pixels": blocks.add(&px),
        }));
    }

    for e in &entries {
        let stem = image_stem(&e.strategy, &e.sampler);
        let path = run_dir.join(format!("{stem}.exr"));
        let bytes = crate::bounded::read_file(&path, 0)?;
        let px = budget.load(&bytes, &path, 3, rgb)?;
        let image = blocks.add(&px);
        let var_path = run_dir.join(format!("{stem}.variance.exr"));
        let variance = if var_path.exists() {
            let bytes = crate::bounded::read_file(&var_path, 0)?;
            let v = budget.load(&bytes, &var_path, 1, rgb)?;
            Some(blocks.add(&mean_of_rgb(&v)))
        } else {
            None
        };
        let flip_path = run_dir.join(format!("{stem}.flip.exr"));
        let flip = if flip_path.exists() {
            let bytes = crate::bounded::read_file(&flip_path, 0)?;
            Some(blocks.add(&budget.load(&bytes, &flip_path, 1, read_flip)?))
        } else {
            None
        };
        images.push(json!({
            "name": stem,
            "kind": "strategy",
            "strategy": e.strategy,
            "sampler": e.sampler,
            "integrand": e.integrand,
            "file": format!("{stem}.exr"),
            "pixels": image,
            "variance": variance,
            "flip": flip,
        }));
    }
    let (width, height) = budget.size.unwrap_or((0, 0));

    let run_id = run_dir
        .canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_default();
    let scene = run
        .get("scene")
        .and_then(Value::as_str)
        .unwrap_or_default()
        .to_string();
    let colormap = |m: colorous::Gradient| -> Vec<u8> {
        (0..256)
            .flat_map(|i| {
                let c = m.eval_continuous(i as f64 / 255.0);
                [c.r, c.g, c.b]
            })
            .collect()
    };
    let data = json!({
        "format": FORMAT,
        "scene": scene,
        "run_id": run_id,
        "width": width,
        "height": height,
        "eps": crate::metrics::EPS,
        "run": run,
        "summary": summary.to_json(),
        "results": results.to_json(),
        "images": images,
        "notes": notes,
        "colormaps": {
            "viridis": colormap(colorous::VIRIDIS),
            "magma": colormap(colorous::MAGMA),
        },
        "generator": format!("dibench {} ({})", crate::harness::VERSION, crate::harness::COMMIT),
    });
    Ok(page(&data, &blocks, &scene, &run_id))
}

/// JSON text safe inside a `<script>` element: `<`, `>` and `&` only occur in strings, where
/// their \u escapes mean the same.
fn script_json(v: &Value) -> String {
    v.to_string()
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026")
}

fn html_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The template with its markers (each once, in this order) replaced.
fn page(data: &Value, blocks: &Blocks, scene: &str, run_id: &str) -> String {
    let mut blob_html = String::new();
    for (id, b64) in &blocks.0 {
        blob_html.push_str(&format!(
            "<script type=\"application/octet-stream\" id=\"{id}\" data-encoding=\"base64-f32le\">{b64}</script>\n"
        ));
    }
    let parts: [(&str, String); 5] = [
        (
            "{{TITLE}}",
            html_text(&format!("dibench · {scene} · {run_id}")),
        ),
        ("/*{{CSS}}*/", CSS.to_string()),
        ("{{DATA}}", script_json(data)),
        ("{{BLOCKS}}", blob_html),
        ("/*{{JS}}*/", JS.to_string()),
    ];
    let mut out =
        String::with_capacity(TEMPLATE.len() + parts.iter().map(|p| p.1.len()).sum::<usize>());
    let mut rest = TEMPLATE;
    for (marker, value) in &parts {
        let at = rest
            .find(marker)
            .unwrap_or_else(|| panic!("assets/report/report.html lacks {marker}"));
        out.push_str(&rest[..at]);
        out.push_str(value);
        rest = &rest[at + marker.len()..];
    }
    out.push_str(rest);
    out
}

/// Writes `RUN_DIR/report.html` (atomically: a temporary file renamed into place) and
/// returns its path.
pub fn write_report(run_dir: &Path) -> Result<PathBuf> {
    let html = build_report(run_dir)?;
    let path = run_dir.join(REPORT);
    crate::output::write_bytes(&path, html.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests;
