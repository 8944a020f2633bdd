//! Log-log plots of error against time (`hppm compare`), drawn with plotters into a PNG. Text
//! uses an embedded DejaVu Sans subset (DejaVuSans-LICENSE.txt), so no system font is needed.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

use crate::Error;

/// One line of the plot: (seconds, relMSE) points, drawn with markers.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub style: SeriesStyle,
    /// Index into the style's colours: a graph's measured and estimated lines share one.
    pub colour: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Measured against a reference: solid line, filled markers.
    Measured,
    /// The render's own estimate: dashed line, hollow markers.
    Estimated,
    /// Measured by another renderer (`--peer`): grey, hollow markers.
    Peer,
}

const FONT: &[u8] = include_bytes!("DejaVuSans-ascii.ttf");
const FAMILY: &str = "hppm-sans";
const SIZE: (u32, u32) = (820, 560);
/// Distinct, print-safe colours for our graphs; peers are drawn in greys.
const COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];
const PEER_COLOURS: [RGBColor; 3] = [
    RGBColor(0, 0, 0),
    RGBColor(110, 110, 110),
    RGBColor(170, 170, 170),
];

fn register_font() -> Result<(), Error> {
    static REGISTER: Once = Once::new();
    let mut result = Ok(());
    REGISTER.call_once(|| {
        result = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).map_err(|_| {
            Error::Other("the embedded plot font is not a valid TrueType font".into())
        });
    });
    result
}

/// Writes a log-log plot of relMSE against seconds to `path` (PNG).
pub fn error_vs_time(path: &Path, title: &str, series: &[Series]) -> Result<(), Error> {
    register_font()?;
    let failed = |e: &dyn std::fmt::Display| Error::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("drawing the plot: {e}")),
    };
    let points = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        return Err(Error::Other(format!(
            "{}: nothing to plot (no positive time and error)",
            path.display()
        )));
    }
    // A decade of margin at most, so single points and flat lines still get an axis.
    let (x0, x1) = (x0 / 1.5, x1 * 1.5);
    let (y0, y1) = (y0 / 2.0, y1 * 2.0);

    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| failed(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| failed(&e))?;
    chart
        .configure_mesh()
        .x_desc("seconds (render time, readback excluded)")
        .y_desc("relMSE")
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .x_label_formatter(&|v| format!("{v}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| failed(&e))?;
    for s in series {
        let color = match s.style {
            SeriesStyle::Peer => PEER_COLOURS[s.colour % PEER_COLOURS.len()],
            _ => COLOURS[s.colour % COLOURS.len()],
        };
        let points: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .collect();
        let drawn = if s.style == SeriesStyle::Estimated {
            let line = DashedLineSeries::new(points.clone(), 8, 5, color.stroke_width(2));
            chart.draw_series(line).map_err(|e| failed(&e))?
        } else {
            let line = LineSeries::new(points.clone(), color.stroke_width(2));
            chart.draw_series(line).map_err(|e| failed(&e))?
        };
        drawn.label(&s.label).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
        });
        let filled = s.style == SeriesStyle::Measured;
        chart
            .draw_series(points.iter().map(|&p| {
                let style = if filled {
                    color.filled()
                } else {
                    color.stroke_width(2)
                };
                Circle::new(p, 4, style)
            }))
            .map_err(|e| failed(&e))?;
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| failed(&e))?;
    root.present().map_err(|e| failed(&e))?;
    Ok(())
}
