//! A live view of a render in tev (Thomas Müller's HDR image viewer) over its TCP protocol, as
//! pbrt-v4's `--display-server` does: the image is created once, then the tiles whose pixels
//! changed since the viewer last got them are sent as the render goes on. A packet is its length
//! (u32, little-endian, the length field included), a type byte and the payload; `CreateImage`
//! (type 4) carries focus, the image's name, width, height and its channels' names,
//! `UpdateImageV3` (6) the same name and channels, the region (x, y, width, height), each
//! channel's offset and stride into the floats that follow. The image's own channels are `R`,
//! `G`, `B`; each further layer (an AOV) adds `LAYER.R`, `LAYER.G`, `LAYER.B`, which tev lists
//! as layers of the one image. A viewer that is not there, goes away or stalls never slows or
//! fails the render: the connection is dropped and tried again a second later (the image is
//! created anew then, and every tile sent).

use std::io::Write;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::image::Image;

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;
const RGB: [&str; 3] = ["R", "G", "B"];
/// Tiles this many pixels on a side are compared with what the viewer holds and sent when any
/// of their values changed: a converged or unsampled region (adaptive sampling, a black sky)
/// costs nothing after its first update.
pub const TILE: u32 = 64;
/// How long a connection attempt or a write may take before the viewer counts as gone.
const PATIENCE: Duration = Duration::from_millis(200);
/// How long after a failure the viewer is tried again.
const RETRY: Duration = Duration::from_secs(1);

/// A tev viewer at an address, sent the image of one render.
pub struct TevView {
    addr: SocketAddr,
    name: String,
    stream: Option<TcpStream>,
    /// What the viewer holds on this connection: size, channels, and their values, every
    /// channel of a pixel together.
    shown: Option<Shown>,
    last_sent: Option<Instant>,
    retry_at: Option<Instant>,
    /// Updates with at least one tile sent, over every connection.
    pub updates: u64,
    /// Tiles sent, over every connection.
    pub tiles_sent: u64,
}

struct Shown {
    width: u32,
    height: u32,
    channels: Vec<String>,
    values: Vec<f32>,
}

/// The image's channels: `R`, `G`, `B` for the unnamed layer, `LAYER.R`, ... for the others.
fn channel_names(layers: &[(&str, &Image)]) -> Vec<String> {
    layers
        .iter()
        .flat_map(|(layer, _)| {
            RGB.map(|c| match layer.is_empty() {
                true => c.to_string(),
                false => format!("{layer}.{c}"),
            })
        })
        .collect()
}

/// Every channel of every layer, pixel by pixel: the layout `UpdateImageV3`'s offsets and
/// strides describe.
fn interleave(layers: &[(&str, &Image)], pixels: usize) -> Vec<f32> {
    let mut values = Vec::with_capacity(pixels * 3 * layers.len());
    for i in 0..pixels {
        for (_, image) in layers {
            values.extend(image.pixels.get(i).copied().unwrap_or([0.0; 3]));
        }
    }
    values
}

/// The tiles of a `width` x `height` image, as (x, y, width, height).
fn tiles(width: u32, height: u32) -> impl Iterator<Item = [u32; 4]> {
    (0..height.div_ceil(TILE)).flat_map(move |ty| {
        (0..width.div_ceil(TILE)).map(move |tx| {
            let (x, y) = (tx * TILE, ty * TILE);
            [x, y, TILE.min(width - x), TILE.min(height - y)]
        })
    })
}

/// The rows of `tile` within a whole image's values.
fn tile_rows(
    values: &[f32],
    width: u32,
    channels: usize,
    tile: [u32; 4],
) -> impl Iterator<Item = &[f32]> {
    let [x, y, w, h] = tile.map(|v| v as usize);
    let row = width as usize * channels;
    (y..y + h).map(move |r| &values[r * row + x * channels..r * row + (x + w) * channels])
}

impl TevView {
    /// A view at `address`, `[HOST:]PORT` (the host defaults to 127.0.0.1), of an image called
    /// `name`. An address that does not resolve is an error; a viewer that does not answer is not.
    pub fn new(address: &str, name: &str) -> Result<Self, crate::Error> {
        let full = if address.contains(':') {
            address.to_string()
        } else {
            format!("127.0.0.1:{address}")
        };
        let addr = full
            .to_socket_addrs()
            .map_err(|e| crate::Error::Other(format!("tev address \"{address}\": {e}")))?
            .next()
            .ok_or_else(|| crate::Error::Other(format!("tev address \"{address}\": no address")))?;
        Ok(Self {
            addr,
            name: name.to_string(),
            stream: None,
            shown: None,
            last_sent: None,
            retry_at: None,
            updates: 0,
            tiles_sent: 0,
        })
    }

    /// The image's name in the viewer.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether an update is due: none sent yet, or `interval` since the last.
    pub fn due(&self, interval: Duration) -> bool {
        self.last_sent.is_none_or(|t| t.elapsed() >= interval)
    }

    /// Sends `image`.
    pub fn show(&mut self, image: &Image) {
        self.show_layers(&[("", image)]);
    }

    /// Sends the tiles of `layers` (the image first, named "", then AOVs by name, all of its
    /// size) that changed since the viewer got them, creating the image first when its size
    /// or layers are new to the viewer; gives up quietly when the viewer is not there.
    pub fn show_layers(&mut self, layers: &[(&str, &Image)]) {
        self.last_sent = Some(Instant::now());
        let Some((_, first)) = layers.first() else {
            return;
        };
        let (width, height) = (first.width, first.height);
        let layers: Vec<(&str, &Image)> = layers
            .iter()
            .copied()
            .filter(|(_, image)| (image.width, image.height) == (width, height))
            .collect();
        if !self.viewer_still_there() && !self.connect() {
            return;
        }
        let channels = channel_names(&layers);
        let values = interleave(&layers, (width as usize) * (height as usize));
        let mut packets = Vec::new();
        let known = self
            .shown
            .as_ref()
            .filter(|s| (s.width, s.height) == (width, height) && s.channels == channels);
        if known.is_none() {
            packets.push(create_packet(&self.name, width, height, &channels));
        }
        let n = channels.len();
        for tile in tiles(width, height) {
            // Compared row by row in place: a tile is copied only when it goes out.
            let changed = known.is_none_or(|s| {
                tile_rows(&values, width, n, tile).ne(tile_rows(&s.values, width, n, tile))
            });
            if changed {
                let now: Vec<f32> = tile_rows(&values, width, n, tile)
                    .flatten()
                    .copied()
                    .collect();
                packets.push(update_packet(&self.name, &channels, tile, &now));
            }
        }
        let sent_tiles = packets.len() - usize::from(known.is_none());
        if packets.is_empty() {
            return;
        }
        let sent = self
            .stream
            .as_mut()
            .is_some_and(|s| packets.iter().all(|p| s.write_all(p).is_ok()));
        if sent {
            self.shown = Some(Shown {
                width,
                height,
                channels,
                values,
            });
            self.updates += u64::from(sent_tiles > 0);
            self.tiles_sent += sent_tiles as u64;
        } else {
            self.drop_connection();
        }
    }

    /// Whether the connection is open at the viewer's end too. tev never writes back, so a
    /// read that finds the end of the stream means it closed (quit or restarted): without this
    /// an image whose tiles stopped changing would send nothing, and a restarted viewer would
    /// never be given it.
    fn viewer_still_there(&mut self) -> bool {
        let Some(stream) = &self.stream else {
            return false;
        };
        let mut byte = [0u8; 1];
        let open = stream.set_nonblocking(true).is_ok()
            && match stream.peek(&mut byte) {
                Ok(0) => false,
                Ok(_) => true,
                Err(e) => e.kind() == std::io::ErrorKind::WouldBlock,
            }
            && stream.set_nonblocking(false).is_ok();
        if !open {
            self.stream = None;
            self.shown = None;
        }
        open
    }

    fn connect(&mut self) -> bool {
        if self.retry_at.is_some_and(|t| Instant::now() < t) {
            return false;
        }
        match TcpStream::connect_timeout(&self.addr, PATIENCE) {
            Ok(stream) => {
                let _ = stream.set_write_timeout(Some(PATIENCE));
                let _ = stream.set_nodelay(true);
                self.stream = Some(stream);
                self.shown = None;
                true
            }
            Err(_) => {
                self.drop_connection();
                false
            }
        }
    }

    fn drop_connection(&mut self) {
        self.stream = None;
        self.shown = None;
        self.retry_at = Some(Instant::now() + RETRY);
    }
}

/// A packet under construction: the length field first, filled in at the end.
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Self {
        let mut bytes = vec![0; 4];
        bytes.push(kind);
        Packet(bytes)
    }
    fn bool(&mut self, v: bool) -> &mut Self {
        self.0.push(v as u8);
        self
    }
    fn string(&mut self, s: &str) -> &mut Self {
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
        self
    }
    fn i32(&mut self, v: i32) -> &mut Self {
        self.0.extend(v.to_le_bytes());
        self
    }
    fn i64(&mut self, v: i64) -> &mut Self {
        self.0.extend(v.to_le_bytes());
        self
    }
    fn finish(mut self) -> Vec<u8> {
        let len = self.0.len() as u32;
        self.0[..4].copy_from_slice(&len.to_le_bytes());
        self.0
    }
}

/// `CreateImage`: an image of `width` x `height` with `channels`, called `name`.
pub fn create_packet(name: &str, width: u32, height: u32, channels: &[String]) -> Vec<u8> {
    let mut p = Packet::new(CREATE_IMAGE);
    p.bool(false)
        .string(name)
        .i32(width as i32)
        .i32(height as i32)
        .i32(channels.len() as i32);
    for c in channels {
        p.string(c);
    }
    p.finish()
}

/// `UpdateImageV3`: the pixels of `tile` (x, y, width, height), `values` holding every channel
/// of a pixel together, row by row (offset c, stride the channel count).
pub fn update_packet(name: &str, channels: &[String], tile: [u32; 4], values: &[f32]) -> Vec<u8> {
    let mut p = Packet::new(UPDATE_IMAGE_V3);
    p.bool(false).string(name).i32(channels.len() as i32);
    for c in channels {
        p.string(c);
    }
    for v in tile {
        p.i32(v as i32);
    }
    for c in 0..channels.len() {
        p.i64(c as i64);
    }
    for _ in channels {
        p.i64(channels.len() as i64);
    }
    p.0.reserve(values.len() * 4);
    for v in values {
        p.0.extend(v.to_le_bytes());
    }
    p.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::net::TcpListener;

    /// The update packets' regions in a stream (after the 4-byte length and the type byte, a
    /// focus byte, the name, the channel count and names come before the region).
    fn regions(bytes: &[u8], channels: usize) -> Vec<[i32; 4]> {
        let mut out = Vec::new();
        let mut rest = bytes;
        while rest.len() >= 5 {
            let len = u32::from_le_bytes(rest[..4].try_into().expect("4")) as usize;
            if rest[4] == UPDATE_IMAGE_V3 {
                let mut at = 6 + rest[6..].iter().position(|&b| b == 0).expect("name") + 1 + 4;
                for _ in 0..channels {
                    at += rest[at..].iter().position(|&b| b == 0).expect("channel") + 1;
                }
                let field = |i: usize| {
                    i32::from_le_bytes(rest[at + 4 * i..at + 4 * i + 4].try_into().expect("4"))
                };
                out.push([field(0), field(1), field(2), field(3)]);
            }
            rest = &rest[len..];
        }
        out
    }

    /// Only tiles whose values changed are sent again: the same image twice sends nothing the
    /// second time, one pixel changed sends its tile alone, a new layer recreates the image and
    /// sends every tile. Catches a view that resends everything or misses a change.
    #[test]
    fn only_changed_tiles_are_sent() {
        let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
        let address = listener.local_addr().expect("addr").to_string();
        let mut view = TevView::new(&address, "tiles").expect("address");
        let mut image = Image {
            width: 130,
            height: 70,
            pixels: vec![[0.5, 0.25, 0.125]; 130 * 70],
        };
        view.show(&image);
        let (mut stream, _) = listener.accept().expect("connection");
        assert_eq!((view.updates, view.tiles_sent), (1, 6)); // 3 x 2 tiles
        view.show(&image);
        assert_eq!((view.updates, view.tiles_sent), (1, 6));
        image.pixels[69 * 130 + 129] = [1.0, 0.0, 0.0];
        view.show(&image);
        assert_eq!((view.updates, view.tiles_sent), (2, 7));
        let aov = image.clone();
        view.show_layers(&[("", &image), ("pt", &aov)]);
        assert_eq!((view.updates, view.tiles_sent), (3, 13));
        drop(view);
        let mut bytes = Vec::new();
        stream.read_to_end(&mut bytes).expect("read");
        // (The last 6 packets have 6 channels: their regions are not read right here.)
        let regions = regions(&bytes, 3);
        assert_eq!(regions.len(), 13, "every tile sent is a packet");
        assert_eq!(
            regions[6],
            [128, 64, 2, 6],
            "the changed corner's tile alone"
        );
    }

    /// A viewer that restarts: the first connection is closed by the viewer, the view notices
    /// on a write, waits, connects again and creates the image anew with every tile, so the new
    /// viewer shows the whole image and not only what changed since. Catches a view that gives
    /// up after one failure or resumes sending tiles to an image the new viewer never created.
    #[test]
    fn a_restarted_viewer_gets_the_image_created_again() {
        let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
        let address = listener.local_addr().expect("addr").to_string();
        let mut view = TevView::new(&address, "restart").expect("address");
        let image = Image {
            width: 100,
            height: 40,
            pixels: vec![[0.25; 3]; 100 * 40],
        };
        view.show(&image);
        let (first, _) = listener.accept().expect("first connection");
        drop(first);
        listener.set_nonblocking(true).expect("nonblocking");
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut second = loop {
            view.show(&image);
            if let Ok((stream, _)) = listener.accept() {
                break stream;
            }
            assert!(Instant::now() < deadline, "the view never reconnected");
            std::thread::sleep(Duration::from_millis(50));
        };
        drop(view);
        second.set_nonblocking(false).expect("blocking");
        let mut bytes = Vec::new();
        second.read_to_end(&mut bytes).expect("read");
        assert_eq!(bytes.get(4), Some(&CREATE_IMAGE), "the image created first");
        assert_eq!(
            regions(&bytes, 3).len(),
            2,
            "both tiles of 100x40 sent again"
        );
    }
}
