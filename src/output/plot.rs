//! Plots of a simulation over time, as SVG or PNG: the declared coordinates in the upper panel
//! and the energy (kinetic, and total when the potential is known) in the lower one.
//!
//! Text is laid out (and, in PNGs, rasterised) with `ab_glyph` from a font embedded in the
//! binary, so plotting needs no system fonts, fontconfig or freetype. The font is DejaVu Sans
//! 2.37 from the `dejavu` crate (the crate itself is MIT/Apache-2.0): Bitstream Vera license
//! with the Arev additions, and DejaVu's changes are in the public domain — a permissive
//! license that allows embedding and redistribution as long as the font is not sold alone and
//! is not modified under the Bitstream Vera names. SVGs name the family `sans-serif`, so their
//! viewers render the text with a font of their own.

use std::fs::File;
use std::io::BufWriter;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

use crate::simulate::run::{Sample, Simulation};

const WIDTH: u32 = 1200;
const HEIGHT: u32 = 900;
/// PNGs are drawn this many times larger and then averaged down, which smooths the lines (the
/// bitmap backend does not anti-alias them).
const SUPERSAMPLING: u32 = 3;
/// Share of the height given to the coordinates panel.
const UPPER_SHARE: f64 = 0.55;
const FONT_FAMILY: &str = "sans-serif";
const CAPTION_SIZE: f64 = 24.0;
const LABEL_SIZE: f64 = 16.0;
const LINE_WIDTH: f64 = 2.0;
/// Legend geometry: sample line length, gap before the label, row height, padding.
const LEGEND_LINE: f64 = 28.0;
const LEGEND_GAP: f64 = 8.0;
const LEGEND_ROW: f64 = 24.0;
const LEGEND_PAD: f64 = 14.0;

/// Tableau 10, the default line colours of matplotlib: distinct and readable on white.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

enum Format {
    Svg,
    Png,
}

/// Draws the simulation's coordinates and energy over time to `path`, an SVG when it ends in
/// `.svg` and a PNG when it ends in `.png`.
pub fn plot(simulation: &Simulation, path: &Path) -> Result<(), String> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let format = match extension.as_deref() {
        Some("svg") => Format::Svg,
        Some("png") => Format::Png,
        _ => {
            return Err("a plot's file name must end in .svg (vector) or .png (bitmap)".to_string())
        }
    };
    if simulation.samples.is_empty() {
        return Err("the simulation has no outputs to plot".to_string());
    }
    register_fonts()?;
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
            draw(&root, simulation, 1.0)?;
            root.present().map_err(|e| e.to_string())
        }
        Format::Png => {
            let (width, height) = (WIDTH * SUPERSAMPLING, HEIGHT * SUPERSAMPLING);
            let mut pixels = vec![0u8; width as usize * height as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
                draw(&root, simulation, SUPERSAMPLING as f64)?;
                root.present().map_err(|e| e.to_string())?;
            }
            write_png(path, &downsample(&pixels, SUPERSAMPLING))
        }
    }
}

/// Registers the embedded font once per process, under the family the plots use.
fn register_fonts() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let registered =
        *REGISTERED.get_or_init(|| register_font(FONT_FAMILY, FontStyle::Normal, dejavu::sans::regular()).is_ok());
    if registered {
        Ok(())
    } else {
        Err("the embedded font could not be loaded".to_string())
    }
}

/// Averages each `factor` × `factor` block of an RGB image `factor` times the plot's size.
fn downsample(rgb: &[u8], factor: u32) -> Vec<u8> {
    let (factor, width, height) = (factor as usize, WIDTH as usize, HEIGHT as usize);
    let big_width = width * factor;
    let mut out = vec![0u8; width * height * 3];
    for y in 0..height {
        for x in 0..width {
            for c in 0..3 {
                let mut sum = 0usize;
                for dy in 0..factor {
                    let row = (y * factor + dy) * big_width;
                    for dx in 0..factor {
                        sum += rgb[(row + x * factor + dx) * 3 + c] as usize;
                    }
                }
                out[(y * width + x) * 3 + c] = ((sum + factor * factor / 2) / (factor * factor)) as u8;
            }
        }
    }
    out
}

fn write_png(path: &Path, rgb: &[u8]) -> Result<(), String> {
    let file = File::create(path).map_err(|e| e.to_string())?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), WIDTH, HEIGHT);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// One line of a panel: its legend label and its points (non-finite values left out).
struct Line {
    label: String,
    points: Vec<(f64, f64)>,
}

impl Line {
    fn new(label: &str, samples: &[Sample], value: impl Fn(&Sample) -> Option<f64>) -> Line {
        let points = samples
            .iter()
            .filter_map(|s| value(s).map(|v| (s.time, v)))
            .filter(|(t, v)| t.is_finite() && v.is_finite())
            .collect();
        Line { label: label.to_string(), points }
    }
}

/// Draws both panels; `scale` multiplies every length (fonts, margins, lines) for supersampling.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, simulation: &Simulation, scale: f64) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let samples = &simulation.samples;
    let coordinates: Vec<Line> = simulation
        .coordinate_names
        .iter()
        .enumerate()
        .map(|(i, name)| Line::new(name, samples, |s| s.coordinates.get(i).copied()))
        .collect();
    let mut energy = vec![Line::new("kinetic", samples, |s| Some(s.kinetic_energy))];
    if samples.iter().any(|s| s.potential_energy.is_some()) {
        energy.push(Line::new("total (kinetic + potential)", samples, |s| {
            s.potential_energy.map(|p| s.kinetic_energy + p)
        }));
    }

    let (_, height) = root.dim_in_pixel();
    let (upper, lower) = root.split_vertically((height as f64 * UPPER_SHARE) as u32);
    // Both panels get a legend column of the same width, so that their time axes line up.
    let upper_rows = legend_rows(&upper, coordinates.len(), scale);
    let label_style = TextStyle::from((FONT_FAMILY, LABEL_SIZE * scale).into_font());
    let mut column = 0u32;
    for line in coordinates.iter().chain(&energy) {
        let (text_width, _) = root.estimate_text_size(&line.label, &label_style).map_err(|e| e.to_string())?;
        column = column.max(text_width);
    }
    let column = column + ((LEGEND_LINE + LEGEND_GAP + LEGEND_PAD) * scale) as u32;
    let columns = coordinates.len().div_ceil(upper_rows).max(1) as u32;
    let legend_width = column * columns + (LEGEND_PAD * scale) as u32;

    let time = time_range(samples);
    panel(&upper, "Coordinates", "coordinate", time.clone(), &coordinates, legend_width, column, scale)?;
    panel(&lower, "Energy", "energy", time, &energy, legend_width, column, scale)
}

/// How many legend rows fit beside a panel's plot.
fn legend_rows<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, lines: usize, scale: f64) -> usize {
    let (_, height) = area.dim_in_pixel();
    let usable = height as f64 - (CAPTION_SIZE + 2.0 * LEGEND_PAD) * scale;
    ((usable / (LEGEND_ROW * scale)).floor().max(1.0) as usize).min(lines.max(1))
}

/// One panel: a caption, axes with a light grid and the lines, and their legend to the right.
#[allow(clippy::too_many_arguments)]
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    y_description: &str,
    time: Range<f64>,
    lines: &[Line],
    legend_width: u32,
    column: u32,
    scale: f64,
) -> Result<(), String> {
    let px = |length: f64| (length * scale).round() as u32;
    let (width, _) = area.dim_in_pixel();
    let (plot_area, legend_area) = area.split_horizontally(width.saturating_sub(legend_width));
    let values = value_range(lines.iter().flat_map(|l| l.points.iter().map(|&(_, v)| v)));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(caption, (FONT_FAMILY, CAPTION_SIZE * scale))
        .margin(px(12.0))
        .x_label_area_size(px(48.0))
        .y_label_area_size(px(90.0))
        .build_cartesian_2d(time, values)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("time")
        .y_desc(y_description)
        .label_style((FONT_FAMILY, LABEL_SIZE * scale))
        .axis_desc_style((FONT_FAMILY, LABEL_SIZE * scale))
        .axis_style(BLACK.stroke_width(px(1.0)))
        .bold_line_style(BLACK.mix(0.15).stroke_width(px(1.0)))
        .light_line_style(BLACK.mix(0.05).stroke_width(px(1.0)))
        .set_all_tick_mark_size(px(5.0))
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, line) in lines.iter().enumerate() {
        let style = PALETTE[i % PALETTE.len()].stroke_width(px(LINE_WIDTH));
        chart.draw_series(LineSeries::new(line.points.iter().copied(), style)).map_err(|e| e.to_string())?;
    }

    // The legend, in columns of as many rows as fit, level with the top of the plot.
    let rows = legend_rows(area, lines.len(), scale);
    let label_style = TextStyle::from((FONT_FAMILY, LABEL_SIZE * scale).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    let top = ((CAPTION_SIZE + 12.0 + LEGEND_PAD) * scale) as i32;
    for (i, line) in lines.iter().enumerate() {
        let x = (column * (i / rows) as u32) as i32 + px(LEGEND_PAD) as i32;
        let y = top + ((i % rows) as f64 * LEGEND_ROW * scale) as i32;
        let style = PALETTE[i % PALETTE.len()].stroke_width(px(LINE_WIDTH + 1.0));
        legend_area
            .draw(&PathElement::new(vec![(x, y), (x + px(LEGEND_LINE) as i32, y)], style))
            .map_err(|e| e.to_string())?;
        let text_x = x + px(LEGEND_LINE + LEGEND_GAP) as i32;
        legend_area.draw_text(&line.label, &label_style, (text_x, y)).map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn time_range(samples: &[Sample]) -> Range<f64> {
    let times = samples.iter().map(|s| s.time).filter(|t| t.is_finite());
    let (start, end) = times.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| (lo.min(t), hi.max(t)));
    if start > end {
        0.0..1.0
    } else if end > start {
        start..end
    } else {
        start..start + 1.0
    }
}

/// The range of the values with a margin of 5% on each side; a constant (or no) value gets a
/// range around it of its own size (at least one unit).
fn value_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return -1.0..1.0;
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()) {
        let half = lo.abs().max(1.0);
        return lo - half..hi + half;
    }
    lo - 0.05 * span..hi + 0.05 * span
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::run::Report;

    fn simulation(count: usize, conservative: bool) -> Simulation {
        let samples = (0..count)
            .map(|k| {
                let t = k as f64 * 0.05;
                let (angle, rate) = (0.8 * (2.0 * t).cos(), -1.6 * (2.0 * t).sin());
                let (slide, slide_rate) = (0.3 * (3.0 * t).sin() + 0.2, 0.9 * (3.0 * t).cos());
                let kinetic = 0.5 * rate * rate + 0.5 * slide_rate * slide_rate;
                Sample {
                    time: t,
                    coordinates: vec![angle, slide],
                    rates: vec![rate, slide_rate],
                    kinetic_energy: kinetic,
                    potential_energy: conservative.then(|| 2.0 - kinetic + 0.01 * t),
                    momentum: [0.0; 6],
                }
            })
            .collect();
        Simulation {
            coordinate_names: vec!["crank.q".to_string(), "slider.x".to_string()],
            samples,
            report: Report {
                integrator: "rk4".to_string(),
                duration: (count.max(1) - 1) as f64 * 0.05,
                steps: count,
                rejected_steps: 0,
                function_evaluations: 4 * count,
                cpu_seconds: 0.0,
                energy_drift: None,
                momentum_drift: None,
                failure: None,
            },
        }
    }

    fn temp_path(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("lsdc-plot-{}-{name}", std::process::id()))
    }

    #[test]
    fn renders_svg_and_png() {
        let simulation = simulation(201, true);
        let svg = temp_path("test.svg");
        plot(&simulation, &svg).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg"));
        for name in &simulation.coordinate_names {
            assert!(text.contains(name.as_str()), "the SVG names {name}");
        }
        assert!(text.contains("total (kinetic + potential)"));

        let png = temp_path("test.png");
        plot(&simulation, &png).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.len() > 1000);
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        std::fs::remove_file(svg).unwrap();
        std::fs::remove_file(png).unwrap();
    }

    #[test]
    fn degenerate_runs_still_plot() {
        // One output, no potential: every range is a single value.
        let path = temp_path("single.png");
        plot(&simulation(1, false), &path).unwrap();
        assert!(std::fs::metadata(&path).unwrap().len() > 0);
        std::fs::remove_file(path).unwrap();
    }

    #[test]
    fn rejects_other_extensions_and_empty_runs() {
        let error = plot(&simulation(3, true), &temp_path("plot.pdf")).unwrap_err();
        assert!(error.contains(".svg") && error.contains(".png"), "{error}");
        assert!(plot(&simulation(3, true), &temp_path("plot")).is_err());
        assert!(plot(&simulation(0, true), &temp_path("empty.svg")).is_err());
    }
}
