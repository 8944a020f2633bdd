//! hppm as a library: render a scene to an image in memory through a bundled graph, then write
//! it. Only the library is needed (`hppm = { default-features = false }` leaves the command
//! line out).
//!
//!     cargo run --release --example render_to_image -- [SCENE] [OUT.png] [SPP]
//!
//! Without arguments it renders hppm's bundled Cornell box (a glass sphere's caustic) at
//! 128x128 and 16 samples per pixel through `graphs/hybrid.ron` into `render_to_image.png`.

use std::path::{Path, PathBuf};

use hppm::gpu::GpuContext;
use hppm::image::{Image, Provenance};
use hppm::passes::Registry;
use hppm::render::Renderer;

/// `scene` through the bundled graph `graph` at `size`, until `spp` samples per pixel.
fn render(
    gpu: &GpuContext,
    scene: &Path,
    graph: &str,
    size: (u32, u32),
    spp: u64,
) -> Result<Image, hppm::Error> {
    let scene = hppm::loaders::load(scene)?;
    let registry = Registry::builtin();
    let graph = registry.bundled_graph(graph)?;
    let mut renderer = Renderer::builder(gpu, &scene, graph)
        .registry(registry)
        .size(size.0, size.1)
        .build()?;
    while renderer.samples_per_pixel() < spp {
        renderer.iterate()?;
    }
    renderer.image()
}

fn main() -> Result<(), hppm::Error> {
    let mut args = std::env::args().skip(1);
    let scene = args
        .next()
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.ron"));
    let out = PathBuf::from(args.next().unwrap_or("render_to_image.png".into()));
    let spp = match args.next() {
        Some(text) => text
            .parse()
            .map_err(|e| hppm::Error::Other(format!("SPP \"{text}\": {e}")))?,
        None => 16,
    };
    let gpu = GpuContext::new(None)?;
    let image = render(&gpu, &scene, "hybrid", (128, 128), spp)?;
    let provenance = Provenance::default().with("adapter", gpu.adapter_label());
    image.write(&out, &provenance)?;
    let mean: f32 = image.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>()
        / (3 * image.pixels.len()) as f32;
    println!(
        "{}: {}x{}, mean {mean:.4}",
        out.display(),
        image.width,
        image.height
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.ron")
    }

    /// The example's path runs: the bundled Cornell box through the bundled hybrid gives a
    /// lit, finite image of the size asked for.
    #[test]
    fn renders_the_bundled_cornell_box() {
        let gpu = GpuContext::new(std::env::var("HPPM_TEST_ADAPTER").ok().as_deref())
            .expect("an adapter");
        let image = render(&gpu, &cornell(), "hybrid", (24, 16), 2).expect("render");
        assert_eq!((image.width, image.height), (24, 16));
        assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
        let lit = image.pixels.iter().filter(|p| p[0] > 0.0).count();
        assert!(lit > image.pixels.len() / 2, "{lit} lit pixels");
    }

    /// A host program's own device: hppm renders on a device it did not open, and (path
    /// tracing being deterministic per pixel) makes the same image it makes on its own.
    #[test]
    fn renders_on_a_device_the_host_opened() {
        let own = GpuContext::new(std::env::var("HPPM_TEST_ADAPTER").ok().as_deref())
            .expect("an adapter");
        let desc = wgpu::DeviceDescriptor {
            label: Some("host"),
            required_features: own.features,
            required_limits: own.limits.clone(),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(own.adapter.request_device(&desc)).expect("host device");
        let host = GpuContext::from_device(own.adapter.clone(), device, queue);
        let a = render(&own, &cornell(), "pt", (16, 16), 4).expect("own device");
        let b = render(&host, &cornell(), "pt", (16, 16), 4).expect("host device");
        assert_eq!(a.pixels, b.pixels);
    }
}
