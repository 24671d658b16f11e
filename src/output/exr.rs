//! RGB EXR files: written as f32 scan lines, read with the header checked before any pixel
//! memory is allocated (a header may claim any size). An image the harness renders carries
//! its [`Provenance`] as header attributes `dibench:<field>` (what `oiiotool --info -v` and
//! the `exr` crate read back).

use crate::bounded;
use crate::error::{Error as DibenchError, Result};
use crate::film::Image as RgbImage;
use std::io::Cursor;
use std::path::Path;

/// How an image was made, written into its EXR header: one text attribute per field
/// (`dibench:strategy`, …; numbers in decimal, the render time in seconds as a double), plus
/// the standard `software` attribute. Text is UTF-8.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Provenance {
    pub scene: String,
    /// The scene's content hash (its TOML and every file it references).
    pub scene_hash: String,
    pub strategy: String,
    pub integrand: String,
    pub sampler: String,
    /// What the pixels are: `radiance` (the mean estimate) or `variance of the mean`.
    pub content: String,
    pub spp: u64,
    /// Render time of the passes in the image, in seconds.
    pub render_time_s: f64,
    pub seed: u64,
    pub backend: String,
    pub threads: usize,
    pub version: String,
    pub commit: String,
    /// The machine that rendered it, as [`crate::harness::cpu_model`] describes it (name,
    /// family, model, stepping, ISA): timings mean nothing without it. A reference merged from
    /// shards names each distinct machine once, in shard order, joined by " | ". None in
    /// images written before it was recorded (no `dibench:cpu` attribute).
    pub cpu: Option<String>,
}

/// The attribute-name prefix of [`Provenance`]'s fields.
pub const ATTRIBUTE_PREFIX: &str = "dibench:";

impl Provenance {
    /// The same provenance for the image's variance-of-the-mean companion.
    pub fn variance(&self) -> Provenance {
        Provenance {
            content: "variance of the mean".into(),
            ..self.clone()
        }
    }

    fn text_fields(&self) -> [(&'static str, String); 12] {
        [
            ("scene", self.scene.clone()),
            ("scene_hash", self.scene_hash.clone()),
            ("strategy", self.strategy.clone()),
            ("integrand", self.integrand.clone()),
            ("sampler", self.sampler.clone()),
            ("content", self.content.clone()),
            ("spp", self.spp.to_string()),
            ("seed", self.seed.to_string()),
            ("backend", self.backend.clone()),
            ("threads", self.threads.to_string()),
            ("version", self.version.clone()),
            ("commit", self.commit.clone()),
        ]
    }

    fn attributes(
        &self,
    ) -> Vec<(
        exr::meta::attribute::Text,
        exr::meta::attribute::AttributeValue,
    )> {
        use exr::meta::attribute::{AttributeValue, Text};
        let name =
            |k: &str| Text::from_slice_unchecked(format!("{ATTRIBUTE_PREFIX}{k}").as_bytes());
        let mut out: Vec<_> = self
            .text_fields()
            .into_iter()
            .map(|(k, v)| {
                (
                    name(k),
                    AttributeValue::Text(Text::from_slice_unchecked(v.as_bytes())),
                )
            })
            .collect();
        out.push((
            name("render_time_s"),
            AttributeValue::F64(self.render_time_s),
        ));
        if let Some(cpu) = &self.cpu {
            out.push((
                name("cpu"),
                AttributeValue::Text(Text::from_slice_unchecked(cpu.as_bytes())),
            ));
        }
        out
    }
}

/// RGB f32 EXR, ZIP-compressed scan lines (tiled files trip up some readers, e.g. tinyexr),
/// written atomically.
pub fn write_exr(path: &Path, img: &RgbImage) -> Result<()> {
    super::write_atomic(path, |file| encode_exr(file, img, path, None))
}

/// [`write_exr`] with the image's provenance in the header.
pub fn write_exr_with(path: &Path, img: &RgbImage, provenance: &Provenance) -> Result<()> {
    super::write_atomic(path, |file| encode_exr(file, img, path, Some(provenance)))
}

/// Writes `img` as an EXR into the open file `to` (errors name `named`), with `provenance`
/// in its header if given: for writers that already write to a temporary file, such as a
/// store commit.
pub fn encode_exr(
    to: &mut std::fs::File,
    img: &RgbImage,
    named: &Path,
    provenance: Option<&Provenance>,
) -> Result<()> {
    use exr::prelude::*;
    {
        let w = img.width as usize;
        let enc = Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let mut attributes = LayerAttributes::default();
        if let Some(p) = provenance {
            attributes.software_name = Some(Text::from_slice_unchecked(
                format!("dibench {} ({})", p.version, p.commit).as_bytes(),
            ));
            attributes.other.extend(p.attributes());
        }
        let layer = Layer::new(
            (w, img.height as usize),
            attributes,
            enc,
            SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = img.pixels[y * w + x];
                (p[0] as f32, p[1] as f32, p[2] as f32)
            }),
        );
        exr::image::Image::from_layer(layer)
            .write()
            .to_buffered(std::io::BufWriter::new(to))
            .map_err(|e| DibenchError::Output {
                path: named.into(),
                message: format!("cannot write EXR: {e}"),
            })
    }
}

/// The [`Provenance`] in the header of the EXR file `path` (None when it has none: written
/// before it was recorded, or by another program); a field that is missing or does not parse
/// is an error naming the file and the attribute. Reads the header only.
pub fn read_provenance(path: &Path) -> Result<Option<Provenance>> {
    use exr::meta::attribute::AttributeValue;
    let bytes = bounded::read_file(path, 0)?;
    let meta =
        exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes[..]), false).map_err(|e| {
            DibenchError::Parse {
                path: path.into(),
                message: format!("not a readable EXR image: {e}"),
            }
        })?;
    let Some(header) = meta.headers.first() else {
        return Ok(None);
    };
    let other = &header.own_attributes.other;
    let get = |k: &str| {
        other
            .iter()
            .find(|(name, _)| name.bytes() == format!("{ATTRIBUTE_PREFIX}{k}").as_bytes())
            .map(|(_, v)| v)
    };
    if get("strategy").is_none() {
        return Ok(None);
    }
    let bad = |k: &str, why: &str| DibenchError::Parse {
        path: path.into(),
        message: format!("header attribute `{ATTRIBUTE_PREFIX}{k}`: {why}"),
    };
    let text = |k: &str| -> Result<String> {
        match get(k) {
            Some(AttributeValue::Text(t)) => Ok(String::from_utf8_lossy(t.bytes()).into_owned()),
            Some(_) => Err(bad(k, "not text")),
            None => Err(bad(k, "missing")),
        }
    };
    let number = |k: &str| -> Result<u64> {
        text(k)?
            .parse::<u64>()
            .map_err(|e| bad(k, &format!("not a whole number: {e}")))
    };
    let render_time_s = match get("render_time_s") {
        Some(AttributeValue::F64(t)) => *t,
        Some(_) => return Err(bad("render_time_s", "not a double")),
        None => return Err(bad("render_time_s", "missing")),
    };
    Ok(Some(Provenance {
        scene: text("scene")?,
        scene_hash: text("scene_hash")?,
        strategy: text("strategy")?,
        integrand: text("integrand")?,
        sampler: text("sampler")?,
        content: text("content")?,
        spp: number("spp")?,
        render_time_s,
        seed: number("seed")?,
        backend: text("backend")?,
        threads: number("threads")? as usize,
        version: text("version")?,
        commit: text("commit")?,
        // Optional: images written before it was recorded have none.
        cpu: get("cpu").map(|_| text("cpu")).transpose()?,
    }))
}

/// Reads the first RGB(A) layer of an EXR file (a regular file, its size and then its header
/// checked before decoding).
pub fn read_exr(path: &Path) -> Result<RgbImage> {
    let bytes = bounded::read_file(path, 0)?;
    let (width, height, pixels) =
        decode_exr(&bytes, path, |r, g, b| [r as f64, g as f64, b as f64])?;
    Ok(RgbImage {
        width: width as u32,
        height: height as u32,
        pixels,
    })
}

/// Decodes the first RGB(A) layer of the EXR `bytes` (read from `path`, which errors name)
/// into row-major pixels made by `pixel`: (width, height, pixels). Before anything is
/// allocated for pixels, every header's block count is checked against the bytes there are
/// (each block needs an 8-byte offset), and the largest layer against available memory.
pub fn decode_exr<T: Clone + Default + 'static>(
    bytes: &[u8],
    path: &Path,
    pixel: fn(f32, f32, f32) -> T,
) -> Result<(usize, usize, Vec<T>)> {
    use exr::prelude::*;
    let unreadable = |e: exr::error::Error| DibenchError::Parse {
        path: path.into(),
        message: format!("not a readable EXR image: {e}"),
    };
    let meta =
        exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(unreadable)?;
    let mut largest = 0u64;
    let mut blocks = 0u64;
    for h in meta.headers.iter() {
        let (w, hgt) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        blocks = blocks.saturating_add(h.chunk_count as u64);
        if bounded::bytes(blocks, 8) > bytes.len() as u64 {
            return Err(DibenchError::Parse {
                path: path.into(),
                message: format!(
                    "the header claims {w}×{hgt} pixels in {} blocks, more than the file's {} \
                     bytes can hold (truncated or damaged)",
                    h.chunk_count,
                    bytes.len()
                ),
            });
        }
        largest = largest.max(w.saturating_mul(hgt));
    }
    // The pixels as built here, plus the decoder's f32 samples of the layer.
    let per_pixel = std::mem::size_of::<T>() as u64 + 16;
    bounded::check_memory(
        || format!("{}: an EXR of {largest} pixels", path.display()),
        bounded::bytes(largest, per_pixel),
    )?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| (res.width(), vec![T::default(); res.width() * res.height()]),
            move |(w, px): &mut (usize, Vec<T>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = pixel(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(unreadable)?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            pixels: (0..w * h)
                .map(|i| [i as f64 * 0.25, 0.0009765625, 7.5e3])
                .collect(),
        }
    }

    #[test]
    fn exr_round_trip_is_exact_for_f32_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let img = image(3, 2);
        write_exr(&path, &img).unwrap();
        assert_eq!(read_exr(&path).unwrap(), img);
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(
            leftovers.len(),
            1,
            "temporary files left behind: {leftovers:?}"
        );
    }

    /// Every field round-trips through the header (a non-ASCII scene name included); an
    /// image written without provenance reads as None; a damaged field is an error naming the
    /// file and the attribute (the negative control: a reader that ignored the fields, or
    /// wrote one under the wrong name, fails the equality).
    #[test]
    fn provenance_round_trips_through_the_header() {
        let dir = tempfile::tempdir().unwrap();
        let p = Provenance {
            scene: "cornell-ü".into(),
            scene_hash: "abc123".into(),
            strategy: "mis-power".into(),
            integrand: "direct".into(),
            sampler: "sobol".into(),
            content: "radiance".into(),
            spp: 1 << 40,
            render_time_s: 1.25,
            seed: u64::MAX,
            backend: "packet".into(),
            threads: 2,
            version: "0.1.0".into(),
            commit: "deadbeef".into(),
            cpu: Some("AMD EPYC (family 25, model 1, stepping 1; avx2)".into()),
        };
        let path = dir.path().join("a.exr");
        write_exr_with(&path, &image(3, 2), &p).unwrap();
        assert_eq!(read_provenance(&path).unwrap(), Some(p.clone()));
        assert_eq!(read_exr(&path).unwrap(), image(3, 2));
        let v = dir.path().join("v.exr");
        write_exr_with(&v, &image(3, 2), &p.variance()).unwrap();
        assert_eq!(
            read_provenance(&v).unwrap().unwrap().content,
            "variance of the mean"
        );
        let plain = dir.path().join("plain.exr");
        write_exr(&plain, &image(3, 2)).unwrap();
        assert_eq!(read_provenance(&plain).unwrap(), None);
        // An image from before the machine was recorded: no `dibench:cpu`, read as None.
        let older = dir.path().join("older.exr");
        let before = Provenance {
            cpu: None,
            ..p.clone()
        };
        write_exr_with(&older, &image(3, 2), &before).unwrap();
        assert_eq!(read_provenance(&older).unwrap(), Some(before));
        // The spp attribute's text damaged in place (same length: "109951162777x").
        let mut bytes = std::fs::read(&path).unwrap();
        let digits = (1u64 << 40).to_string();
        let at = bytes
            .windows(digits.len())
            .position(|w| w == digits.as_bytes())
            .unwrap();
        bytes[at + digits.len() - 1] = b'x';
        let bad = dir.path().join("bad.exr");
        std::fs::write(&bad, &bytes).unwrap();
        let e = read_provenance(&bad).unwrap_err().to_string();
        assert!(e.contains("bad.exr") && e.contains("dibench:spp"), "{e}");
    }

    #[test]
    fn truncated_exr_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        std::fs::write(&path, b"v/1\x01\x02\x00\x00").unwrap();
        let err = read_exr(&path).unwrap_err().to_string();
        assert!(err.contains("bad.exr"), "{err}");
    }

    /// A header whose data window claims 2^29 rows (EXR allows up to 2^30) is refused before
    /// any pixel memory is allocated; the same file with its true size reads.
    #[test]
    fn a_header_claiming_more_than_the_file_holds_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("liar.exr");
        write_exr(&path, &image(4, 4)).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        assert!(decode_exr(&bytes, &path, |r, _, _| r).is_ok());
        // dataWindow is a box2i: xMin, yMin, xMax, yMax after its name, type and size.
        let at = bytes.windows(10).position(|w| w == b"dataWindow").unwrap();
        let y_max = at + b"dataWindow\0box2i\0".len() + 4 + 12;
        bytes[y_max..y_max + 4].copy_from_slice(&(1i32 << 29).to_le_bytes());
        let msg = decode_exr(&bytes, &path, |r, _, _| r)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("liar.exr") && msg.contains("more than the file"),
            "{msg}"
        );
    }
}
