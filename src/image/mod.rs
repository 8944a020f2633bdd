//! Images: EXR (linear f32 RGB) and PNG (sRGB) output, EXR input, error metrics.

use std::path::{Path, PathBuf};

use crate::Error;

/// A linear RGB image, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// Text recorded in every written file (EXR attributes, PNG text chunks): which adapter made it.
#[derive(Debug, Clone, Default)]
pub struct Provenance {
    pub entries: Vec<(String, String)>,
}

impl Provenance {
    pub fn with(mut self, key: &str, value: impl ToString) -> Self {
        self.entries.push((key.to_string(), value.to_string()));
        self
    }
}

/// Errors of an image against a reference (`Image::metrics_where`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorMetrics {
    /// Mean of (x - r)^2 / (r^2 + 0.01): the reference set's metric (tests/refs/README.md).
    pub relmse: f64,
    /// Root of the mean of (x - r)^2.
    pub rmse: f64,
    /// Mean of |x - r|.
    pub mae: f64,
    /// Pixels the means ran over.
    pub pixels: usize,
}

fn io_error(path: &Path, message: impl ToString) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(message.to_string()),
    }
}

impl Image {
    /// Averages per-pixel (sum, count) accumulators; pixels with no sample are black.
    pub fn from_sums(width: u32, height: u32, sums: &[[f32; 4]]) -> Self {
        let pixels = sums
            .iter()
            .map(|&[r, g, b, n]| {
                if n > 0.0 {
                    [r / n, g / n, b / n]
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        Self {
            width,
            height,
            pixels,
        }
    }

    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += p[c] as f64;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        sum.map(|s| s / n)
    }

    /// Relative MSE against `reference`: mean over pixels and RGB of (x-r)^2/(r^2+0.01), the
    /// metric of the reference set (tests/refs/README.md).
    pub fn relmse(&self, reference: &Image) -> Result<f64, Error> {
        self.relmse_where(reference, |_| true)
    }

    /// Relative MSE over the pixels (row-major indices) for which `keep` holds.
    pub fn relmse_where(
        &self,
        reference: &Image,
        keep: impl Fn(usize) -> bool,
    ) -> Result<f64, Error> {
        Ok(self.metrics_where(reference, keep)?.relmse)
    }

    /// relMSE, RMSE and mean absolute error against `reference`, each a mean over the kept
    /// pixels and their RGB channels.
    pub fn metrics_where(
        &self,
        reference: &Image,
        keep: impl Fn(usize) -> bool,
    ) -> Result<ErrorMetrics, Error> {
        self.check_same_size(reference)?;
        let (mut relative, mut squared, mut absolute) = (0.0f64, 0.0f64, 0.0f64);
        let mut count = 0usize;
        for (i, (x, r)) in self.pixels.iter().zip(&reference.pixels).enumerate() {
            if !keep(i) {
                continue;
            }
            count += 1;
            for c in 0..3 {
                let (x, r) = (x[c] as f64, r[c] as f64);
                relative += (x - r) * (x - r) / (r * r + 0.01);
                squared += (x - r) * (x - r);
                absolute += (x - r).abs();
            }
        }
        let n = (3 * count.max(1)) as f64;
        Ok(ErrorMetrics {
            relmse: relative / n,
            rmse: (squared / n).sqrt(),
            mae: absolute / n,
            pixels: count,
        })
    }

    fn check_same_size(&self, other: &Image) -> Result<(), Error> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(Error::Other(format!(
                "image sizes differ: {}x{} vs {}x{}",
                self.width, self.height, other.width, other.height
            )));
        }
        Ok(())
    }

    /// Reads the first RGB(A) layer of an EXR file.
    pub fn read_exr(path: &Path) -> Result<Image, Error> {
        use exr::prelude::*;
        let image = read_first_rgba_layer_from_file(
            path,
            |resolution, _| {
                (
                    resolution.width(),
                    vec![[0.0f32; 3]; resolution.width() * resolution.height()],
                )
            },
            |(width, pixels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = [r, g, b];
            },
        )
        .map_err(|e| io_error(path, e))?;
        let size = image.layer_data.size;
        Ok(Self {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: image.layer_data.channel_data.pixels.1,
        })
    }

    /// Writes EXR or PNG by the extension of `path`, through a temporary file renamed into
    /// place, so an interrupted run never leaves a truncated image.
    pub fn write(&self, path: &Path, provenance: &Provenance) -> Result<(), Error> {
        let format = OutputFormat::of(path)?;
        write_atomically(path, |temp| match format {
            OutputFormat::Exr => self.write_exr(temp, provenance),
            OutputFormat::Png => self.write_png(temp, provenance),
        })
    }

    fn write_exr(&self, path: &Path, provenance: &Provenance) -> Result<(), Error> {
        use exr::prelude::*;
        let width = self.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let [r, g, b] = self.pixels[y * width + x];
            (r, g, b)
        });
        let mut image = exr::image::Image::from_channels((width, self.height as usize), channels);
        image.layer_data.attributes.software_name = Text::new_or_none("hppm");
        for (key, value) in &provenance.entries {
            if let (Some(k), Some(v)) = (Text::new_or_none(key), Text::new_or_none(value)) {
                image
                    .attributes
                    .other
                    .insert(k, exr::meta::attribute::AttributeValue::Text(v));
            }
        }
        image.write().to_file(path).map_err(|e| io_error(path, e))
    }

    fn write_png(&self, path: &Path, provenance: &Provenance) -> Result<(), Error> {
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| p.map(linear_to_srgb8))
            .collect();
        let file = std::fs::File::create(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        for (key, value) in &provenance.entries {
            // tEXt holds Latin-1 only; a scene path in Cyrillic goes into an iTXt chunk (UTF-8).
            let latin1 = value.chars().all(|c| (c as u32) < 256);
            let added = if latin1 {
                encoder.add_text_chunk(key.clone(), value.clone())
            } else {
                encoder.add_itxt_chunk(key.clone(), value.clone())
            };
            added.map_err(|e| io_error(path, e))?;
        }
        let mut writer = encoder.write_header().map_err(|e| io_error(path, e))?;
        writer
            .write_image_data(&bytes)
            .map_err(|e| io_error(path, e))?;
        writer.finish().map_err(|e| io_error(path, e))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    Exr,
    Png,
}

impl OutputFormat {
    /// The format named by a file's extension; checked before rendering so a typo costs nothing.
    pub fn of(path: &Path) -> Result<Self, Error> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("exr") => Ok(Self::Exr),
            Some("png") => Ok(Self::Png),
            _ => Err(io_error(
                path,
                "unknown image format: use a .exr (linear float) or .png (sRGB) file name",
            )),
        }
    }
}

/// The temporary file beside `path`, `out.png` -> `.out.1234.tmp.png`: hidden (the leading
/// dot), so that a glob over finished files (`merge shards/shard-*.hppm`) never picks up one a
/// killed process left behind, and with `path`'s extension, which writers go by.
fn temp_path(path: &Path) -> PathBuf {
    let mut name = std::ffi::OsString::from(".");
    name.push(path.file_stem().unwrap_or_default());
    name.push(format!(".{}.tmp", std::process::id()));
    if let Some(ext) = path.extension() {
        name.push(".");
        name.push(ext);
    }
    path.with_file_name(name)
}

/// Writes `path` through `write` on a temporary file beside it, renamed into place only once
/// complete, so an interrupted or failed write never leaves a truncated or half-old file.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), Error>,
) -> Result<(), Error> {
    let temp = temp_path(path);
    if let Err(e) = write(&temp) {
        let _ = std::fs::remove_file(&temp);
        return Err(e);
    }
    std::fs::rename(&temp, path).map_err(|source| {
        let _ = std::fs::remove_file(&temp);
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Writes `bytes` to `path` atomically (see `write_atomically`).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomically(path, |temp| {
        std::fs::write(temp, bytes).map_err(|source| Error::Io {
            path: temp.to_path_buf(),
            source,
        })
    })
}

/// Fails unless a file can be created in `path`'s folder: checked before a render, so a missing
/// or read-only folder costs nothing instead of the finished image.
pub fn check_writable(path: &Path) -> Result<(), Error> {
    let probe = temp_path(path);
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    std::fs::File::create(&probe).map_err(io)?;
    std::fs::remove_file(&probe).map_err(io)
}

/// The sRGB transfer curve, clamped to [0, 1], rounded to 8 bits. NaN maps to 0.
fn linear_to_srgb8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A write that fails halfway leaves the old file as it was and no temporary file behind;
    /// one that succeeds replaces it whole.
    #[test]
    fn atomic_writes_replace_whole_files_or_nothing() {
        let dir = std::env::temp_dir().join(format!("hppm-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("errors.csv");
        std::fs::write(&path, "old").expect("old file");
        let failed = write_atomically(&path, |temp| {
            std::fs::write(temp, "half").expect("partial write");
            Err(Error::Other("disk full".into()))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "old");
        let left: Vec<_> = std::fs::read_dir(&dir).expect("list").flatten().collect();
        assert_eq!(left.len(), 1, "a temporary file was left behind");
        write_file_atomically(&path, b"new").expect("write");
        assert_eq!(std::fs::read_to_string(&path).expect("read"), "new");
        // Writers that pick the format by extension see the real one; a glob over the
        // finished files (`shard-*.hppm`, as merge.sbatch's) never matches a left-over one.
        let temp = temp_path(Path::new("a/shard-1.hppm"));
        let name = temp
            .file_name()
            .expect("a name")
            .to_string_lossy()
            .to_string();
        assert!(
            name.ends_with(".hppm") && name.starts_with(".shard-1."),
            "{name}"
        );
        assert_eq!(temp.parent(), Some(Path::new("a")));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
