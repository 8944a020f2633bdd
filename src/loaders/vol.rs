//! Mitsuba's binary grid volumes (`.vol`), the files its `gridvolume` plugin reads: smoke
//! densities, albedo grids. Every format fact here is from Mitsuba 3's documentation of the
//! plugin (src/volumes/grid.cpp) and its reader and writer (src/render/volumegrid.cpp).
//!
//! The layout, all little-endian:
//!
//! | bytes   | content                                                           |
//! |---------|-------------------------------------------------------------------|
//! | 0..3    | ASCII `V`, `O`, `L`                                               |
//! | 3       | version, a byte: 3                                                |
//! | 4..8    | encoding, `i32`: 1 (float32; the only one Mitsuba reads)          |
//! | 8..20   | cells along x, y, z: three `i32`                                  |
//! | 20..24  | channels, `i32`                                                   |
//! | 24..48  | bounding box, six `f32`: xmin, ymin, zmin, xmax, ymax, zmax       |
//! | 48..    | x * y * z * channels `f32`, x fastest, channels interleaved       |
//!
//! Mitsuba checks the magic, the version and the encoding, and fails on a file that ends early;
//! it reads 1, 3 or 6 channels, and does not look at sizes (a zero crashes it), at trailing bytes
//! (ignored) or at the values (negative ones and NaN are taken as they are). This reader is
//! stricter, for the renderer's sake: 1 or 3 channels (6 are SGGX phase-function parameters,
//! which it has no use for), every axis at least one cell, at most [`MAX_VALUES`] values, the
//! file exactly as long as the header says, and every value finite and non-negative. The
//! bounding box is kept as read and not checked: Mitsuba 3 ignores it unless `use_grid_bbox`
//! (see [`crate::scene::grid`]).

use std::io::{Read, Write};
use std::path::Path;

use glam::Vec3;

use crate::scene::grid::Grid;

/// Bytes before the values.
pub const HEADER_BYTES: usize = 48;

/// The most values (cells times channels) a file may hold: 2^30, 4 GiB of `f32`. A header
/// claiming more is refused before anything is allocated.
pub const MAX_VALUES: u64 = 1 << 30;

const VERSION: u8 = 3;
const ENCODING_FLOAT32: i32 = 1;

/// What the 48-byte header says.
struct Header {
    size: [u32; 3],
    channels: u32,
    bbox_min: Vec3,
    bbox_max: Vec3,
    /// Cells times channels.
    values: u64,
}

impl Header {
    /// The whole file's length the header calls for.
    fn file_bytes(&self) -> u64 {
        HEADER_BYTES as u64 + 4 * self.values
    }
}

/// Reads a `.vol` file into a [`Grid`]. Errors are one sentence each, starting with the file's
/// path (a caller puts the scene's place in front); nothing in the file can make this panic,
/// and the values are only allocated once the file is known to hold them all.
pub fn read_vol(path: &Path) -> Result<Grid, String> {
    let name = path.display();
    let mut file = std::fs::File::open(path)
        .map_err(|e| format!("cannot open grid volume file {name}: {e}"))?;
    let read_error = |e: std::io::Error| format!("cannot read grid volume file {name}: {e}");
    let mut head = Vec::with_capacity(HEADER_BYTES);
    (&mut file)
        .take(HEADER_BYTES as u64)
        .read_to_end(&mut head)
        .map_err(read_error)?;
    // The length the file system reports, to refuse a short or long file before allocating.
    let on_disk = file.metadata().map_err(read_error)?.len();
    let header = parse_header(&head, on_disk).map_err(|m| format!("{name}: {m}"))?;
    check_length(&header, on_disk).map_err(|m| format!("{name}: {m}"))?;
    // Read one byte more than the header calls for, in case the file grew meanwhile.
    let body_bytes = header.file_bytes() - HEADER_BYTES as u64;
    let mut body = Vec::with_capacity(body_bytes as usize);
    file.take(body_bytes + 1)
        .read_to_end(&mut body)
        .map_err(read_error)?;
    check_length(&header, HEADER_BYTES as u64 + body.len() as u64)
        .map_err(|m| format!("{name}: {m}"))?;
    grid_from(header, &body).map_err(|m| format!("{name}: {m}"))
}

/// [`read_vol`] for a file's bytes already in memory; the errors leave out the path.
pub fn parse_vol(bytes: &[u8]) -> Result<Grid, String> {
    let header = parse_header(bytes, bytes.len() as u64)?;
    check_length(&header, bytes.len() as u64)?;
    grid_from(header, &bytes[HEADER_BYTES..])
}

/// Writes `grid` as a `.vol` file (version 3, float32), as Mitsuba's `VolumeGrid::write` does.
/// Fails without writing on a grid that does not hold together ([`Grid::check`]) or is too large
/// for the format's `i32` sizes; its values are written as they are.
pub fn write_vol(path: &Path, grid: &Grid) -> std::io::Result<()> {
    let bytes = encode_vol(grid)?;
    let mut file = std::fs::File::create(path)?;
    file.write_all(&bytes)?;
    file.flush()
}

/// The bytes of the `.vol` file [`write_vol`] writes.
pub fn encode_vol(grid: &Grid) -> std::io::Result<Vec<u8>> {
    let invalid = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, m);
    grid.check().map_err(invalid)?;
    let mut header = [0i32; 4];
    for (k, &s) in grid.size.iter().chain([&grid.channels]).enumerate() {
        header[k] = i32::try_from(s)
            .map_err(|_| invalid(format!("size {s} does not fit the format's i32")))?;
    }
    let mut out = Vec::with_capacity(HEADER_BYTES + 4 * grid.data.len());
    out.extend_from_slice(b"VOL");
    out.push(VERSION);
    out.extend_from_slice(&ENCODING_FLOAT32.to_le_bytes());
    for v in header {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in grid
        .bbox_min
        .to_array()
        .into_iter()
        .chain(grid.bbox_max.to_array())
    {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in &grid.data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    Ok(out)
}

/// The header from the file's first bytes (`head`, up to 48 of the `file_len`), checked field by
/// field in file order, so that a file that is not a volume at all is called that rather than
/// short.
fn parse_header(head: &[u8], file_len: u64) -> Result<Header, String> {
    let short = || {
        format!(
            "the file is {file_len} bytes, shorter than the {HEADER_BYTES}-byte header of a \
             .vol file"
        )
    };
    let field = |at: usize| -> Result<[u8; 4], String> {
        head.get(at..at + 4)
            .map(|b| [b[0], b[1], b[2], b[3]])
            .ok_or_else(short)
    };
    let int = |at: usize| field(at).map(i32::from_le_bytes);
    let float = |at: usize| field(at).map(f32::from_le_bytes);

    let magic = head.get(..3).unwrap_or(head);
    if magic != b"VOL" {
        return Err(if head.len() < 3 && b"VOL".starts_with(magic) {
            short()
        } else {
            format!(
                "not a Mitsuba grid volume: it starts with {} instead of \"VOL\"",
                show_bytes(magic)
            )
        });
    }
    let version = *head.get(3).ok_or_else(short)?;
    if version != VERSION {
        return Err(format!(
            "unsupported .vol version {version}: only version {VERSION} is supported, as in \
             Mitsuba 3"
        ));
    }
    let encoding = int(4)?;
    if encoding != ENCODING_FLOAT32 {
        return Err(format!(
            "unsupported encoding {encoding}: only 1 (float32) is supported, as in Mitsuba 3"
        ));
    }
    let res = [int(8)?, int(12)?, int(16)?];
    if res.iter().any(|&r| r < 1) {
        return Err(format!(
            "resolution {}x{}x{}: every axis needs at least one cell",
            res[0], res[1], res[2]
        ));
    }
    let channels = int(20)?;
    if channels != 1 && channels != 3 {
        let what = if channels == 6 {
            " (6 are SGGX phase-function parameters, which are not supported)"
        } else {
            ""
        };
        return Err(format!(
            "{channels} channels{what}: only 1 (a scalar such as density) or 3 (RGB) are \
             supported"
        ));
    }
    // Each factor is below 2^31, so the product of four fits in u128 with room to spare.
    let values = res.iter().map(|&r| r as u128).product::<u128>() * channels as u128;
    if values > MAX_VALUES as u128 {
        return Err(format!(
            "resolution {}x{}x{} with {channels} channel(s) is {values} values, more than the \
             {MAX_VALUES} (4 GiB) accepted",
            res[0], res[1], res[2]
        ));
    }
    let bbox = [
        float(24)?,
        float(28)?,
        float(32)?,
        float(36)?,
        float(40)?,
        float(44)?,
    ];
    Ok(Header {
        size: res.map(|r| r as u32),
        channels: channels as u32,
        bbox_min: Vec3::new(bbox[0], bbox[1], bbox[2]),
        bbox_max: Vec3::new(bbox[3], bbox[4], bbox[5]),
        values: values as u64,
    })
}

/// That a file of `found` bytes is exactly as long as `header` says.
fn check_length(header: &Header, found: u64) -> Result<(), String> {
    let expected = header.file_bytes();
    let [x, y, z] = header.size;
    let what = format!(
        "{x}x{y}x{z} cells of {} channel(s) need {expected} bytes ({HEADER_BYTES} of header and \
         {} values of 4 bytes)",
        header.channels, header.values
    );
    if found < expected {
        Err(format!(
            "truncated: {what}, but the file has {found} ({} missing)",
            expected - found
        ))
    } else if found > expected {
        Err(format!(
            "{} trailing bytes after the values: {what}, but the file has {found}",
            found - expected
        ))
    } else {
        Ok(())
    }
}

/// The grid of `header` from exactly its values' bytes, each value checked.
fn grid_from(header: Header, body: &[u8]) -> Result<Grid, String> {
    let data: Vec<f32> = body
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    if let Some((i, &v)) = data
        .iter()
        .enumerate()
        .find(|&(_, &v)| !v.is_finite() || v < 0.0)
    {
        let channels = header.channels as usize;
        let [nx, ny, _] = header.size.map(|s| s as usize);
        let cell = i / channels;
        let (x, y, z) = (cell % nx, cell / nx % ny, cell / (nx * ny));
        let channel = if channels > 1 {
            format!(" channel {}", i % channels)
        } else {
            String::new()
        };
        return Err(format!(
            "value {i} (cell x={x} y={y} z={z}{channel}) is {v}: grid values must be finite and \
             non-negative"
        ));
    }
    Ok(Grid {
        size: header.size,
        channels: header.channels,
        data,
        bbox_min: header.bbox_min,
        bbox_max: header.bbox_max,
    })
}

/// Up to the first three bytes, printable ASCII as text, the rest in hex.
fn show_bytes(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "nothing (the file is empty)".into();
    }
    let shown: Vec<String> = bytes
        .iter()
        .map(|&b| {
            if b.is_ascii_graphic() {
                format!("'{}'", b as char)
            } else {
                format!("0x{b:02x}")
            }
        })
        .collect();
    shown.join(" ")
}
