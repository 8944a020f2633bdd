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
/// channels, the region, the region's values with every channel of a pixel together).
#[derive(Debug)]
enum Packet {
    Create(String, i32, i32, Vec<String>),
    Update(String, Vec<String>, [i32; 4], Vec<f32>),
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

/// Every packet of a stream, checked for a length that covers exactly its payload and for
/// offsets and strides that stay inside its floats.
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
                let region = [r.i32(), r.i32(), r.i32(), r.i32()];
                let offsets: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| r.i64()).collect();
                let floats: Vec<f32> = (0..r.0.len() / 4).map(|_| r.f32()).collect();
                let pixels = (region[2] * region[3]) as usize;
                let values = (0..pixels)
                    .flat_map(|i| {
                        (0..n)
                            .map(|c| floats[(offsets[c] + i as i64 * strides[c]) as usize])
                            .collect::<Vec<_>>()
                    })
                    .collect();
                Packet::Update(name, channels, region, values)
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

/// What a viewer shows after `packets`, as tev keeps it: per image name, its size, channels and
/// values (every channel of a pixel together), and how many updates it got. An update before
/// its image's creation, with other channels, or outside the image fails.
#[derive(Debug, Default)]
struct Viewer {
    images: std::collections::BTreeMap<String, Shown>,
}

#[derive(Debug)]
struct Shown {
    width: usize,
    channels: Vec<String>,
    values: Vec<f32>,
    updates: usize,
    regions: Vec<[i32; 4]>,
}

impl Viewer {
    fn apply(&mut self, packets: &[Packet]) {
        for packet in packets {
            match packet {
                Packet::Create(name, w, h, channels) => {
                    let values = vec![f32::NAN; (w * h) as usize * channels.len()];
                    let shown = Shown {
                        width: *w as usize,
                        channels: channels.clone(),
                        values,
                        updates: 0,
                        regions: Vec::new(),
                    };
                    self.images.insert(name.clone(), shown);
                }
                Packet::Update(name, channels, region, values) => {
                    let shown = self.images.get_mut(name).expect("created before updated");
                    assert_eq!(&shown.channels, channels);
                    let n = channels.len();
                    let [x, y, w, h] = region.map(|v| v as usize);
                    assert!(
                        x + w <= shown.width && (y + h) * shown.width * n <= shown.values.len()
                    );
                    for row in 0..h {
                        let to = ((y + row) * shown.width + x) * n;
                        shown.values[to..to + w * n]
                            .copy_from_slice(&values[row * w * n..(row + 1) * w * n]);
                    }
                    shown.updates += 1;
                    shown.regions.push(*region);
                }
            }
        }
    }

    /// The RGB of `layer` ("" for the image's own channels).
    fn layer(&self, name: &str, layer: &str) -> Vec<[f32; 3]> {
        let shown = &self.images[name];
        let n = shown.channels.len();
        let at = |c: &str| {
            let full = if layer.is_empty() {
                c.to_string()
            } else {
                format!("{layer}.{c}")
            };
            shown
                .channels
                .iter()
                .position(|x| *x == full)
                .expect("the layer's channel")
        };
        let idx = [at("R"), at("G"), at("B")];
        shown.values.chunks(n).map(|p| idx.map(|i| p[i])).collect()
    }
}

/// Accepts every connection to `listener` and reads each to its end, until `done` is set and
/// the senders have closed.
fn receive_all(
    listener: TcpListener,
    done: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> std::thread::JoinHandle<Vec<Vec<u8>>> {
    std::thread::spawn(move || {
        listener.set_nonblocking(true).expect("nonblocking");
        let mut readers = Vec::new();
        loop {
            match listener.accept() {
                Ok((mut stream, _)) => {
                    stream.set_nonblocking(false).expect("blocking");
                    readers.push(std::thread::spawn(move || {
                        let mut bytes = Vec::new();
                        stream.read_to_end(&mut bytes).expect("read");
                        bytes
                    }));
                }
                Err(_) if done.load(std::sync::atomic::Ordering::SeqCst) => break,
                Err(_) => std::thread::sleep(std::time::Duration::from_millis(5)),
            }
        }
        readers
            .into_iter()
            .map(|r| r.join().expect("reader"))
            .collect()
    })
}

fn render(out: &PathBuf, tev: Option<u16>, extra: &[&str]) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_hppm"));
    cmd.current_dir(common::repo_path("."))
        .args(["render", "scenes/cornell_box.ron"])
        .args(["--size", "80x70", "--spp", "24", "--seed", "5", "--out"])
        .arg(out)
        .args(extra);
    if !extra.contains(&"--graph") {
        cmd.args(["--graph", "graphs/pt.ron"]);
    }
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

/// Runs `render` with a receiver listening and returns what the viewer shows at the end.
fn render_watched(out: &PathBuf, extra: &[&str]) -> Viewer {
    let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
    let port = listener.local_addr().expect("addr").port();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let receiver = receive_all(listener, done.clone());
    render(out, Some(port), extra);
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    let mut viewer = Viewer::default();
    for stream in receiver.join().expect("receiver") {
        let packets = decode(&stream);
        assert!(
            matches!(packets.first(), Some(Packet::Create(..))),
            "a connection starts with the image's creation"
        );
        viewer.apply(&packets);
    }
    viewer
}

/// A receiver listening: the image is created (80x70, R, G, B, named after the output file),
/// updated by tiles on tev's 64-pixel grid (so an 80x70 image is 4 tiles), at least twice (the
/// first iteration and the end), and what the viewer shows at the end is the EXR written,
/// float for float.
#[test]
fn a_listening_viewer_gets_the_image_created_and_updated() {
    let dir = std::env::temp_dir().join(format!("hppm_tev_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("live.exr");
    let viewer = render_watched(&out, &[]);
    let shown = &viewer.images["live.exr"];
    assert_eq!(shown.channels, ["R", "G", "B"]);
    assert_eq!(shown.width, 80);
    let tiles = [
        [0, 0, 64, 64],
        [64, 0, 16, 64],
        [0, 64, 64, 6],
        [64, 64, 16, 6],
    ];
    assert!(
        shown.regions.iter().all(|r| tiles.contains(r)),
        "{:?}",
        shown.regions
    );
    assert!(
        shown.updates >= 2 * tiles.len(),
        "{} tile updates",
        shown.updates
    );
    let written = Image::read_exr(&out).expect("the written image");
    assert_eq!(viewer.layer("live.exr", ""), written.pixels);
    let _ = std::fs::remove_dir_all(&dir);
}

/// With `--aovs` the output node's other images are layers of the one image (`pt.R`, ...), and
/// at the end each layer is the AOV file written: the hybrid's `pt` and `caustic` (which differ,
/// so a layer sent under another's name fails).
#[test]
fn aovs_are_layers_of_the_live_image() {
    let dir = std::env::temp_dir().join(format!("hppm_tev_aovs_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("hybrid.exr");
    let viewer = render_watched(&out, &["--graph", "graphs/hybrid.ron", "--aovs"]);
    let shown = &viewer.images["hybrid.exr"];
    for layer in ["pt", "caustic"] {
        assert!(
            shown.channels.contains(&format!("{layer}.G")),
            "{:?}",
            shown.channels
        );
        let written = Image::read_exr(&dir.join(format!("hybrid.{layer}.exr"))).expect("AOV file");
        assert_eq!(
            viewer.layer("hybrid.exr", layer),
            written.pixels,
            "layer {layer}"
        );
    }
    let written = Image::read_exr(&out).expect("the image");
    assert_eq!(viewer.layer("hybrid.exr", ""), written.pixels);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `hppm compare --tev`: the reference and one image per graph, named by the graphs' labels,
/// each ending as the EXR compare writes for it.
#[test]
fn compare_shows_each_graph_and_the_reference() {
    let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
    let port = listener.local_addr().expect("addr").port();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let receiver = receive_all(listener, done.clone());
    let dir = std::env::temp_dir().join(format!("hppm_tev_compare_{}", std::process::id()));
    let scene = "tests/refs/scenes/cornell_diffuse/scene.xml";
    let reference = "tests/refs/images/cornell_diffuse.exr";
    let run = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .current_dir(common::repo_path("."))
        .args(["compare", scene, "--reference", reference])
        .args(["--graph", "graphs/pt.ron", "--graph", "graphs/hybrid.ron"])
        .args([
            "--time",
            "1",
            "--snapshots",
            "3",
            "--tev",
            &port.to_string(),
            "--out",
        ])
        .arg(&dir)
        .output()
        .expect("run hppm compare");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    let mut viewer = Viewer::default();
    for stream in receiver.join().expect("receiver") {
        viewer.apply(&decode(&stream));
    }
    let names: Vec<&String> = viewer.images.keys().collect();
    assert_eq!(names, ["hybrid", "pt", "reference"]);
    let expected = Image::read_exr(&common::repo_path(reference)).expect("reference");
    assert_eq!(viewer.layer("reference", ""), expected.pixels);
    for label in ["pt", "hybrid"] {
        let shown = &viewer.images[label];
        assert!(
            shown.updates >= 3,
            "{label}: {} tile updates",
            shown.updates
        );
        let written = Image::read_exr(&dir.join(format!("{label}.exr"))).expect("compare's image");
        assert_eq!(viewer.layer(label, ""), written.pixels, "{label}");
    }
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
    render(&with, Some(port), &[]);
    render(&without, None, &[]);
    let a = Image::read_exr(&with).expect("with");
    let b = Image::read_exr(&without).expect("without");
    assert_eq!(a.pixels, b.pixels);
    let _ = std::fs::remove_dir_all(&dir);
}
