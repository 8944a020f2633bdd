//! A live view of a render in tev (Thomas Müller's HDR image viewer) over its TCP protocol, as
//! pbrt-v4's `--display-server` does: the image is created once, then its pixels are sent again
//! as the render goes on. A packet is its length (u32, little-endian, the length field
//! included), a type byte and the payload; `CreateImage` (type 4) carries focus, the image's
//! name, width, height and its channels' names, `UpdateImageV3` (6) the same name and channels,
//! the region (x, y, width, height), each channel's offset and stride into the floats that
//! follow. A viewer that is not there, goes away or stalls never slows or fails the render: the
//! connection is dropped and tried again a second later (the image is created anew then).

use std::io::Write;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use crate::image::Image;

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;
const CHANNELS: [&str; 3] = ["R", "G", "B"];
/// How long a connection attempt or a write may take before the viewer counts as gone.
const PATIENCE: Duration = Duration::from_millis(200);
/// How long after a failure the viewer is tried again.
const RETRY: Duration = Duration::from_secs(1);

/// A tev viewer at an address, sent the image of one render.
pub struct TevView {
    addr: SocketAddr,
    name: String,
    stream: Option<TcpStream>,
    /// The size the viewer's image was created with on this connection.
    created: Option<(u32, u32)>,
    last_sent: Option<Instant>,
    retry_at: Option<Instant>,
    /// Updates sent so far (over every connection).
    pub updates: u64,
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
            created: None,
            last_sent: None,
            retry_at: None,
            updates: 0,
        })
    }

    /// Whether an update is due: none sent yet, or `interval` since the last.
    pub fn due(&self, interval: Duration) -> bool {
        self.last_sent.is_none_or(|t| t.elapsed() >= interval)
    }

    /// Sends `image` (creating it in the viewer first when needed); gives up quietly when the
    /// viewer is not there.
    pub fn show(&mut self, image: &Image) {
        self.last_sent = Some(Instant::now());
        if self.stream.is_none() && !self.connect() {
            return;
        }
        let size = (image.width, image.height);
        let mut packets = Vec::new();
        if self.created != Some(size) {
            packets.push(create_packet(&self.name, image.width, image.height));
        }
        packets.push(update_packet(&self.name, image));
        let sent = self
            .stream
            .as_mut()
            .is_some_and(|s| packets.iter().all(|p| s.write_all(p).is_ok()));
        if sent {
            self.created = Some(size);
            self.updates += 1;
        } else {
            self.drop_connection();
        }
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
                self.created = None;
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
        self.created = None;
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

/// `CreateImage`: an RGB image of `width` x `height` called `name`.
pub fn create_packet(name: &str, width: u32, height: u32) -> Vec<u8> {
    let mut p = Packet::new(CREATE_IMAGE);
    p.bool(false)
        .string(name)
        .i32(width as i32)
        .i32(height as i32)
        .i32(CHANNELS.len() as i32);
    for c in CHANNELS {
        p.string(c);
    }
    p.finish()
}

/// `UpdateImageV3`: every pixel of `image`, its channels interleaved (offset c, stride 3).
pub fn update_packet(name: &str, image: &Image) -> Vec<u8> {
    let mut p = Packet::new(UPDATE_IMAGE_V3);
    p.bool(false).string(name).i32(CHANNELS.len() as i32);
    for c in CHANNELS {
        p.string(c);
    }
    p.i32(0)
        .i32(0)
        .i32(image.width as i32)
        .i32(image.height as i32);
    for c in 0..CHANNELS.len() {
        p.i64(c as i64);
    }
    for _ in CHANNELS {
        p.i64(CHANNELS.len() as i64);
    }
    p.0.reserve(image.pixels.len() * 12);
    for pixel in &image.pixels {
        for v in pixel {
            p.0.extend(v.to_le_bytes());
        }
    }
    p.finish()
}
