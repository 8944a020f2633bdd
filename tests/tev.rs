//! `hppm render --tev`: the live view speaks tev's protocol (a receiver here decodes every
//! packet as tev's own reader does), its last update is the image written, and a render with no
//! viewer listening is the render without one.

use std::io::Read;
use std::net::TcpListener;
use std::path::PathBuf;
use std::process::Command;

use hppm::image::Image;

mod common;

/// One decoded packet: `CreateImage` (name, width, height, channels) or `UpdateImageV3` (name,
/// the region, the pixels as RGB).
#[derive(Debug)]
enum Packet {
    Create(String, i32, i32, Vec<String>),
    Update(String, [i32; 4], Vec<[f32; 3]>),
}

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().expect("4 bytes"))
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().expect("8 bytes"))
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().expect("4 bytes"))
    }
    fn string(&mut self) -> String {
        let end = self.0.iter().position(|&b| b == 0).expect("a NUL");
        let s = String::from_utf8(self.take(end).to_vec()).expect("utf-8");
        self.take(1);
        s
    }
}

/// Every packet of a stream, checked for a length that covers exactly its payload.
fn decode(bytes: &[u8]) -> Vec<Packet> {
    let mut packets = Vec::new();
    let mut rest = bytes;
    while rest.len() >= 4 {
        let len = u32::from_le_bytes(rest[..4].try_into().expect("4")) as usize;
        assert!(
            len >= 5 && len <= rest.len(),
            "packet length {len} of {}",
            rest.len()
        );
        let mut r = Reader(&rest[4..len]);
        let kind = r.u8();
        let _focus = r.u8();
        let name = r.string();
        let packet = match kind {
            4 => {
                let (w, h, n) = (r.i32(), r.i32(), r.i32());
                Packet::Create(name, w, h, (0..n).map(|_| r.string()).collect())
            }
            6 => {
                let n = r.i32() as usize;
                let channels: Vec<String> = (0..n).map(|_| r.string()).collect();
                assert_eq!(channels, ["R", "G", "B"]);
                let region = [r.i32(), r.i32(), r.i32(), r.i32()];
                let offsets: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let floats: Vec<f32> = (0..r.0.len() / 4).map(|_| r.f32()).collect();
                let pixels = (region[2] * region[3]) as usize;
                let rgb = (0..pixels)
                    .map(|i| {
                        std::array::from_fn(|c| {
                            floats[(offsets[c] + i as i64 * strides[c]) as usize]
                        })
                    })
                    .collect();
                Packet::Update(name, region, rgb)
            }
            other => panic!("unexpected packet type {other}"),
        };
        assert!(r.0.is_empty(), "{} bytes left in a packet", r.0.len());
        packets.push(packet);
        rest = &rest[len..];
    }
    assert!(rest.is_empty(), "a partial packet at the end");
    packets
}

fn render(out: &PathBuf, tev: Option<u16>) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hppm"));
    cmd.current_dir(common::repo_path("."))
        .args([
            "render",
            "scenes/cornell_box.ron",
            "--graph",
            "graphs/pt.ron",
        ])
        .args(["--size", "40x30", "--spp", "24", "--seed", "5", "--out"])
        .arg(out);
    if let Some(port) = tev {
        cmd.args(["--tev", &format!("127.0.0.1:{port}")]);
    }
    let run = cmd.output().expect("run hppm");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// A receiver listening: the image is created once (40x30, R, G, B, named after the output
/// file), then updated at least twice (the first iteration and the end), every update covers
/// the whole image, and the last one is the EXR written, float for float.
#[test]
fn a_listening_viewer_gets_the_image_created_and_updated() {
    let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
    let port = listener.local_addr().expect("addr").port();
    let receiver = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().expect("a connection");
        let mut bytes = Vec::new();
        stream.read_to_end(&mut bytes).expect("read");
        bytes
    });
    let dir = std::env::temp_dir().join(format!("hppm_tev_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("live.exr");
    render(&out, Some(port));
    let packets = decode(&receiver.join().expect("receiver"));
    let Some(Packet::Create(name, 40, 30, channels)) = packets.first() else {
        panic!(
            "first packet: {:?}",
            packets.first().map(|_| "not a 40x30 creation")
        );
    };
    assert_eq!(name, "live.exr");
    assert_eq!(channels, &["R", "G", "B"]);
    let updates: Vec<&Vec<[f32; 3]>> = packets
        .iter()
        .filter_map(|p| match p {
            Packet::Update(n, region, rgb) if n == "live.exr" => {
                assert_eq!(region, &[0, 0, 40, 30]);
                Some(rgb)
            }
            _ => None,
        })
        .collect();
    assert!(updates.len() >= 2, "{} updates", updates.len());
    let written = Image::read_exr(&out).expect("the written image");
    assert_eq!(
        updates.last().map(|u| u.as_slice()),
        Some(written.pixels.as_slice())
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nothing listening on the port: the render succeeds and writes the same image as without
/// `--tev` (path tracing with one seed is deterministic).
#[test]
fn no_viewer_leaves_the_render_as_it_is() {
    let port = TcpListener::bind("127.0.0.1:0")
        .expect("listen")
        .local_addr()
        .expect("addr")
        .port();
    let dir = std::env::temp_dir().join(format!("hppm_tev_none_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let (with, without) = (dir.join("with.exr"), dir.join("without.exr"));
    render(&with, Some(port));
    render(&without, None);
    let a = Image::read_exr(&with).expect("with");
    let b = Image::read_exr(&without).expect("without");
    assert_eq!(a.pixels, b.pixels);
    let _ = std::fs::remove_dir_all(&dir);
}
