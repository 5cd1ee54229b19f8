//! Plots of a simulation over time, as SVG or PNG: the declared coordinates and the program's
//! named outputs in the upper panel and the energy (kinetic, and total when the potential is
//! known) in the lower one, or the columns a user chooses, in panels of their own.
//!
//! Text is laid out (and, in PNGs, rasterised) with `ab_glyph` from a font embedded in the
//! binary, so plotting needs no system fonts, fontconfig or freetype. The font is DejaVu Sans
//! 2.37 from the `dejavu` crate (the crate itself is MIT/Apache-2.0): Bitstream Vera license
//! with the Arev additions, and DejaVu's changes are in the public domain — a permissive
//! license that allows embedding and redistribution as long as the font is not sold alone and
//! is not modified under the Bitstream Vera names. SVGs name the family `sans-serif`, so their
//! viewers render the text with a font of their own.

use std::error::Error;
use std::fmt;
use std::fs::File;
use std::io::BufWriter;
use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

use super::plot_columns::Column;
use crate::simulate::run::{Sample, Simulation};

/// The width of a plot, in pixels.
pub const WIDTH: u32 = 1200;
/// The height of a plot, in pixels.
pub const HEIGHT: u32 = 900;
/// PNGs are drawn this many times larger and then averaged down, which smooths the lines (the
/// bitmap backend does not anti-alias them).
const SUPERSAMPLING: u32 = 3;
/// SVG user units per pixel of the SVG's displayed size (its `viewBox` is this much larger).
const SVG_UNITS_PER_PIXEL: u32 = 4;
/// Share of the height given to the coordinates panel.
const UPPER_SHARE: f64 = 0.55;
pub const FONT_FAMILY: &str = "sans-serif";
pub(super) const CAPTION_SIZE: f64 = 24.0;
pub(super) const LABEL_SIZE: f64 = 16.0;
pub(super) const LINE_WIDTH: f64 = 2.0;
/// Legend geometry: sample line length, gap before the label, row height, padding.
const LEGEND_LINE: f64 = 28.0;
const LEGEND_GAP: f64 = 8.0;
const LEGEND_ROW: f64 = 24.0;
const LEGEND_PAD: f64 = 14.0;
/// The bitmap backend's vertically centred text sits this share of its size too high (SVG
/// viewers centre on the x-height themselves).
const BITMAP_CENTRE_SHIFT: f64 = 0.14;

/// Tableau 10, the default line colours of matplotlib: distinct and readable on white.
pub(super) const PALETTE: [RGBColor; 10] = [
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
pub fn plot(simulation: &Simulation, path: &Path) -> Result<(), PlotError> {
    plot_columns(simulation, path, &[])
}

/// As [`plot`], with only the chosen columns (`columns`, from
/// [`resolve`](super::plot_columns::resolve)), each group in a panel of its own; the
/// coordinates, outputs and energy when `columns` is empty.
pub fn plot_columns(
    simulation: &Simulation,
    path: &Path,
    columns: &[Vec<Column>],
) -> Result<(), PlotError> {
    format_of(path)?;
    if simulation.samples.is_empty() {
        return Err(PlotError::NoOutputs);
    }
    write_figure(&OverTime(simulation, columns), path)
}

/// Checks that a plot's file name ends in `.svg` or `.png`, before the work that the plot shows.
pub fn check_file_name(path: &Path) -> Result<(), PlotError> {
    format_of(path).map(|_| ())
}

/// The format a plot's file name asks for.
fn format_of(path: &Path) -> Result<Format, PlotError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => Err(PlotError::UnknownFormat),
    }
}

/// Checks before a run that a plot can be written to `path`: its name asks for an image this
/// module draws, and the file can be created (it is, empty, until the plot is drawn).
pub fn check_path(path: &Path) -> Result<(), PlotError> {
    check_file_name(path)?;
    std::fs::File::create(path).map_err(PlotError::Io)?;
    Ok(())
}

/// A drawing that `write_figure` renders into an SVG or a PNG.
pub(super) trait Figure {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        render: Render,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static;
}

/// The coordinates and the energy of a simulation over time, or the columns chosen.
struct OverTime<'s>(&'s Simulation, &'s [Vec<Column>]);

impl Figure for OverTime<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        render: Render,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let panels = match self.1 {
            [] => standard_panels(self.0),
            chosen => chosen_panels(self.0, chosen),
        };
        let times: Vec<f64> = self.0.samples.iter().map(|s| s.time).collect();
        draw(root, &times, &panels, render)
    }
}

/// Series over time in panels of their own: a caption, and a label and a value per time for
/// each line (`lsdc sensitivity --plot`).
pub struct Series {
    pub caption: String,
    pub lines: Vec<(String, Vec<f64>)>,
}

/// Draws `series` at `times` to `path`, an SVG or a PNG as for [`plot`], the panels sharing
/// the height equally.
pub fn plot_series(path: &Path, times: &[f64], series: &[Series]) -> Result<(), PlotError> {
    format_of(path)?;
    if times.is_empty() {
        return Err(PlotError::NoOutputs);
    }
    write_figure(&SeriesOverTime(times, series), path)
}

struct SeriesOverTime<'s>(&'s [f64], &'s [Series]);

impl Figure for SeriesOverTime<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        render: Render,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let SeriesOverTime(times, series) = *self;
        let panels: Vec<Panel> = (series.iter())
            .map(|panel| Panel {
                caption: panel.caption.clone(),
                quantity: "derivative",
                lines: (panel.lines.iter())
                    .map(|(label, values)| Line::from_points(label, times, values))
                    .collect(),
                share: 1.0 / series.len().max(1) as f64,
            })
            .collect();
        draw(root, times, &panels, render)
    }
}

/// Draws `figure` to `path`, an SVG when it ends in `.svg` and a PNG when it ends in `.png`.
pub(super) fn write_figure(figure: &impl Figure, path: &Path) -> Result<(), PlotError> {
    let format = format_of(path)?;
    register_fonts()?;
    match format {
        Format::Svg => {
            // Drawn in a finer grid than it is shown in, since the backend rounds every point to
            // the grid: at 1 unit per pixel the curves would come out as staircases.
            let (width, height) = (WIDTH * SVG_UNITS_PER_PIXEL, HEIGHT * SVG_UNITS_PER_PIXEL);
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
                figure.draw(
                    &root,
                    Render {
                        scale: SVG_UNITS_PER_PIXEL as f64,
                        bitmap: false,
                    },
                )?;
                root.present().map_err(PlotError::drawing)?;
            }
            let svg = svg.replacen(
                &format!("<svg width=\"{width}\" height=\"{height}\""),
                &format!("<svg width=\"{WIDTH}\" height=\"{HEIGHT}\""),
                1,
            );
            std::fs::write(path, svg).map_err(PlotError::Io)
        }
        Format::Png => {
            let (width, height) = (WIDTH * SUPERSAMPLING, HEIGHT * SUPERSAMPLING);
            let mut pixels = vec![0u8; width as usize * height as usize * 3];
            {
                let root =
                    BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
                figure.draw(
                    &root,
                    Render {
                        scale: SUPERSAMPLING as f64,
                        bitmap: true,
                    },
                )?;
                root.present().map_err(PlotError::drawing)?;
            }
            write_png(path, &downsample(&pixels, SUPERSAMPLING))
        }
    }
}

/// Why a plot could not be drawn or written.
#[derive(Debug)]
pub enum PlotError {
    /// The file name ends in neither `.svg` nor `.png`.
    UnknownFormat,
    /// The simulation has no samples.
    NoOutputs,
    /// The embedded font could not be registered with the plotting library.
    Font,
    /// The plotting library failed while drawing.
    Drawing(Box<dyn Error + Send + Sync>),
    Io(std::io::Error),
    Png(png::EncodingError),
}

impl PlotError {
    pub(super) fn drawing<E: Error + Send + Sync + 'static>(
        error: DrawingAreaErrorKind<E>,
    ) -> PlotError {
        PlotError::Drawing(Box::new(error))
    }
}

impl fmt::Display for PlotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlotError::UnknownFormat => write!(
                f,
                "a plot's file name must end in .svg (vector) or .png (bitmap)"
            ),
            PlotError::NoOutputs => write!(f, "the simulation has no outputs to plot"),
            PlotError::Font => write!(f, "the embedded font could not be loaded"),
            PlotError::Drawing(e) => write!(f, "{e}"),
            PlotError::Io(e) => write!(f, "{e}"),
            PlotError::Png(e) => write!(f, "{e}"),
        }
    }
}

impl Error for PlotError {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        match self {
            PlotError::Drawing(e) => Some(e.as_ref()),
            PlotError::Io(e) => Some(e),
            PlotError::Png(e) => Some(e),
            _ => None,
        }
    }
}

/// Registers the embedded font once per process, under the family the plots use
/// (`FONT_FAMILY`); also for other plots drawn with plotters (the benchmarks').
pub fn register_fonts() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let registered = *REGISTERED.get_or_init(|| {
        register_font(FONT_FAMILY, FontStyle::Normal, dejavu::sans::regular()).is_ok()
    });
    if registered {
        Ok(())
    } else {
        Err(PlotError::Font)
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
                out[(y * width + x) * 3 + c] =
                    ((sum + factor * factor / 2) / (factor * factor)) as u8;
            }
        }
    }
    out
}

fn write_png(path: &Path, rgb: &[u8]) -> Result<(), PlotError> {
    let file = File::create(path).map_err(PlotError::Io)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), WIDTH, HEIGHT);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(PlotError::Png)?;
    writer.write_image_data(rgb).map_err(PlotError::Png)?;
    writer.finish().map_err(PlotError::Png)
}

/// One line of a panel: its legend label, its points (non-finite values left out) and whether
/// it is dashed (so that a line drawn over another identical one leaves it visible).
struct Line {
    label: String,
    points: Vec<(f64, f64)>,
    dashed: bool,
}

impl Line {
    fn new(label: &str, samples: &[Sample], value: impl Fn(&Sample) -> Option<f64>) -> Line {
        let times: Vec<f64> = samples.iter().map(|s| s.time).collect();
        let values: Vec<f64> = (samples.iter())
            .map(|s| value(s).unwrap_or(f64::NAN))
            .collect();
        Line::from_points(label, &times, &values)
    }

    /// A line through the points (times[k], values[k]), the non-finite ones left out.
    fn from_points(label: &str, times: &[f64], values: &[f64]) -> Line {
        let points = (times.iter().copied().zip(values.iter().copied()))
            .filter(|(t, v)| t.is_finite() && v.is_finite())
            .collect();
        Line {
            label: label.to_string(),
            points,
            dashed: false,
        }
    }
}

/// How the plot is rendered: `scale` multiplies every length (fonts, margins, lines) for a
/// supersampled bitmap or a fine SVG grid, and `bitmap` tells that the text is rasterised here
/// rather than by an SVG viewer.
#[derive(Clone, Copy)]
pub(super) struct Render {
    scale: f64,
    bitmap: bool,
}

impl Render {
    pub(super) fn px(self, length: f64) -> u32 {
        (length * self.scale).round() as u32
    }

    pub(super) fn font(self, size: f64) -> TextStyle<'static> {
        TextStyle::from((FONT_FAMILY, size * self.scale).into_font())
    }
}

/// The layout both panels share, so that their time axes line up.
struct Layout {
    render: Render,
    time: Axis,
    y_label_width: u32,
    legend_width: u32,
    legend_column: u32,
    legend_columns: usize,
}

/// One panel of a plot: its caption, what its values are, its lines and its share of the
/// height.
struct Panel {
    caption: String,
    quantity: &'static str,
    lines: Vec<Line>,
    share: f64,
}

/// The plot without a choice of columns: the declared coordinates and the program's named
/// outputs above, the energy (kinetic, and total when the potential is known) below.
fn standard_panels(simulation: &Simulation) -> Vec<Panel> {
    let samples = &simulation.samples;
    let coordinates: Vec<Line> = (simulation.coordinate_names.iter().enumerate())
        .map(|(i, name)| Line::new(name, samples, |s| s.coordinates.get(i).copied()))
        .chain(
            (simulation.output_names.iter().enumerate())
                .map(|(i, name)| Line::new(name, samples, |s| s.outputs.get(i).copied())),
        )
        .collect();
    let mut energy = vec![Line::new("kinetic", samples, |s| Some(s.kinetic_energy))];
    if samples.iter().any(|s| s.potential_energy.is_some()) {
        let mut total = Line::new("total (kinetic + potential)", samples, |s| {
            s.potential_energy.map(|p| s.kinetic_energy + p)
        });
        total.dashed = true;
        energy.push(total);
    }
    let (caption, quantity) = if simulation.output_names.is_empty() {
        ("Coordinates", "coordinate")
    } else {
        ("Coordinates and outputs", "value")
    };
    vec![
        Panel {
            caption: caption.to_string(),
            quantity,
            lines: coordinates,
            share: UPPER_SHARE,
        },
        Panel {
            caption: "Energy".to_string(),
            quantity: "energy",
            lines: energy,
            share: 1.0 - UPPER_SHARE,
        },
    ]
}

/// The chosen columns, a panel per group, the panels sharing the height equally; each panel is
/// captioned with its columns' names.
fn chosen_panels(simulation: &Simulation, groups: &[Vec<Column>]) -> Vec<Panel> {
    let samples = &simulation.samples;
    (groups.iter())
        .map(|columns| Panel {
            caption: (columns.iter().map(|c| c.name.as_str()))
                .collect::<Vec<_>>()
                .join(", "),
            quantity: "value",
            lines: (columns.iter())
                .map(|column| Line::new(&column.name, samples, |s| column.value(s)))
                .collect(),
            share: 1.0 / groups.len() as f64,
        })
        .collect()
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    times: &[f64],
    panels: &[Panel],
    render: Render,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let error = PlotError::drawing::<DB::ErrorType>;
    root.fill(&WHITE).map_err(error)?;
    let axes: Vec<Axis> = (panels.iter())
        .map(|panel| Axis::new(values(&panel.lines), true))
        .collect();
    // The panels' areas, top to bottom, by their shares of the height.
    let (width, height) = root.dim_in_pixel();
    let mut areas = Vec::new();
    let mut rest = root.clone();
    for panel in &panels[..panels.len().saturating_sub(1)] {
        let (area, below) = rest.split_vertically((height as f64 * panel.share) as u32);
        areas.push(area);
        rest = below;
    }
    areas.push(rest);
    let label_style = render.font(LABEL_SIZE);
    let text_width = |text: &str| {
        root.estimate_text_size(text, &label_style)
            .map(|(w, _)| w)
            .map_err(error)
    };
    let mut y_label_width = 0;
    for axis in &axes {
        for value in [axis.range.start, axis.range.end] {
            y_label_width = y_label_width.max(text_width(&axis.label(value))?);
        }
    }
    let mut legend_column = 0;
    for line in panels.iter().flat_map(|p| &p.lines) {
        legend_column = legend_column.max(text_width(&line.label)?);
    }
    let legend_column = legend_column + render.px(LEGEND_LINE + LEGEND_GAP + LEGEND_PAD);
    // As many columns as the most crowded panel needs, within half the width.
    let needed = (panels.iter().zip(&areas))
        .map(|(panel, area)| {
            let lines = panel.lines.len();
            lines.div_ceil(legend_rows(area, lines, render))
        })
        .max()
        .unwrap_or(1)
        .max(1) as u32;
    let columns =
        needed.min(((width / 2).saturating_sub(render.px(LEGEND_PAD)) / legend_column).max(1));
    let layout = Layout {
        render,
        time: Axis::new(times.iter().copied(), false),
        y_label_width,
        legend_width: legend_column * columns + render.px(LEGEND_PAD),
        legend_column,
        legend_columns: columns as usize,
    };
    for ((panel, axis), area) in panels.iter().zip(&axes).zip(&areas) {
        let caption = &panel.caption;
        self::panel(area, caption, panel.quantity, axis, &panel.lines, &layout)?;
    }
    Ok(())
}

fn values(lines: &[Line]) -> impl Iterator<Item = f64> + '_ {
    lines.iter().flat_map(|l| l.points.iter().map(|&(_, v)| v))
}

/// How many legend rows fit beside a panel's plot.
fn legend_rows<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    lines: usize,
    render: Render,
) -> usize {
    let (_, height) = area.dim_in_pixel();
    let usable = height as f64 - (CAPTION_SIZE + 2.0 * LEGEND_PAD) * render.scale;
    ((usable / (LEGEND_ROW * render.scale)).floor().max(1.0) as usize).min(lines.max(1))
}

/// One panel: a caption, axes with a light grid and the lines, and their legend to the right.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    caption: &str,
    y_description: &str,
    axis: &Axis,
    lines: &[Line],
    layout: &Layout,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let error = PlotError::drawing::<DB::ErrorType>;
    let render = layout.render;
    let px = |length: f64| render.px(length);
    let (width, _) = area.dim_in_pixel();
    let (plot_area, legend_area) =
        area.split_horizontally(width.saturating_sub(layout.legend_width));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(caption, render.font(CAPTION_SIZE))
        .margin(px(12.0))
        .x_label_area_size(px(48.0))
        .y_label_area_size(layout.y_label_width + px(44.0))
        .build_cartesian_2d(layout.time.range.clone(), axis.range.clone())
        .map_err(error)?;
    let x_label = |t: &f64| layout.time.label(*t);
    let y_label = |v: &f64| axis.label(*v);
    chart
        .configure_mesh()
        .x_desc("time")
        .y_desc(axis.description(y_description))
        .x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .label_style(render.font(LABEL_SIZE))
        .axis_desc_style(render.font(LABEL_SIZE))
        .axis_style(BLACK.stroke_width(px(1.0)))
        .bold_line_style(BLACK.mix(0.15).stroke_width(px(1.0)))
        .light_line_style(BLACK.mix(0.05).stroke_width(px(1.0)))
        .set_all_tick_mark_size(px(5.0))
        .draw()
        .map_err(error)?;
    for (i, line) in lines.iter().enumerate() {
        let style = PALETTE[i % PALETTE.len()].stroke_width(px(LINE_WIDTH));
        let points = line.points.iter().map(|&(t, v)| (t, v - axis.offset));
        if line.dashed {
            chart
                .draw_series(DashedLineSeries::new(points, px(10.0), px(6.0), style))
                .map_err(error)?;
        } else {
            chart
                .draw_series(LineSeries::new(points, style))
                .map_err(error)?;
        }
    }

    // The legend, in columns of as many rows as fit, level with the top of the plot; when the
    // lines are too many for it, its last entry says how many it leaves out.
    let rows = legend_rows(area, lines.len(), render);
    let capacity = rows * layout.legend_columns;
    let shown = if lines.len() > capacity {
        capacity - 1
    } else {
        lines.len()
    };
    let label_style = render
        .font(LABEL_SIZE)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let top = ((CAPTION_SIZE + 12.0 + LEGEND_PAD) * render.scale) as i32;
    let text_shift = if render.bitmap {
        (BITMAP_CENTRE_SHIFT * LABEL_SIZE * render.scale) as i32
    } else {
        0
    };
    let position = |i: usize| {
        let x = (layout.legend_column * (i / rows) as u32 + px(LEGEND_PAD)) as i32;
        (
            x,
            top + ((i % rows) as f64 * LEGEND_ROW * render.scale) as i32,
        )
    };
    if shown < lines.len() {
        let (x, y) = position(shown);
        let text = format!("… and {} more", lines.len() - shown);
        legend_area
            .draw_text(&text, &label_style, (x, y + text_shift))
            .map_err(error)?;
    }
    for (i, line) in lines.iter().enumerate().take(shown) {
        let (x, y) = position(i);
        let style = PALETTE[i % PALETTE.len()].stroke_width(px(LINE_WIDTH + 1.0));
        let length = px(LEGEND_LINE) as i32;
        if line.dashed {
            let (dash, gap) = (px(10.0) as i32, px(6.0) as i32);
            for start in (0..length).step_by((dash + gap) as usize) {
                let end = (start + dash).min(length);
                legend_area
                    .draw(&PathElement::new(vec![(x + start, y), (x + end, y)], style))
                    .map_err(error)?;
            }
        } else {
            legend_area
                .draw(&PathElement::new(vec![(x, y), (x + length, y)], style))
                .map_err(error)?;
        }
        let text_x = x + px(LEGEND_LINE + LEGEND_GAP) as i32;
        legend_area
            .draw_text(&line.label, &label_style, (text_x, y + text_shift))
            .map_err(error)?;
    }
    Ok(())
}

/// Most significant digits a tick label may need before the axis shows its values relative to
/// an offset (as in "energy − 4.0052") instead.
const MAX_DIGITS: i32 = 6;
/// The number of labelled ticks plotters puts on an axis at most.
const MAX_TICKS: f64 = 11.0;

/// A value axis: the plotted range, the offset subtracted from the values to get it, and how its
/// tick labels are written.
pub struct Axis {
    /// The plotted range, of the values less the offset.
    pub range: Range<f64>,
    /// The offset subtracted from the values.
    pub offset: f64,
    offset_text: String,
    /// The step between labelled ticks.
    step: f64,
    /// How the tick labels are written.
    pub format: LabelFormat,
}

/// How the tick labels of an axis are written.
#[derive(Debug, PartialEq)]
pub enum LabelFormat {
    /// This many decimals.
    Fixed(usize),
    /// Scientific notation with this many decimals in the mantissa.
    Scientific(usize),
}

impl Axis {
    /// The axis over the finite values, with a margin of 5% on each side when `margin`; a
    /// constant (or no) value gets a range around it of its own size, at least one unit.
    pub fn new(values: impl Iterator<Item = f64>, margin: bool) -> Axis {
        let (lo, hi) = values
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if lo > hi {
            return Axis::plain(-1.0..1.0);
        }
        let span = hi - lo;
        let magnitude = lo.abs().max(hi.abs());
        if span <= 1e-13 * magnitude || span == 0.0 {
            let half = if margin { magnitude.max(1.0) } else { 1.0 };
            return Axis::plain(if margin {
                lo - half..hi + half
            } else {
                lo..hi + half
            });
        }
        let pad = if margin { 0.05 * span } else { 0.0 };
        let (lo, hi) = (lo - pad, hi + pad);
        let step = tick_step(lo, hi);
        if magnitude.log10().floor() - step.log10().floor() + 1.0 <= MAX_DIGITS as f64 {
            return Axis::plain(lo..hi);
        }
        let unit = 10f64.powf(span.log10().floor() + 1.0);
        let offset = ((lo + hi) / 2.0 / unit).round() * unit;
        let decimals = (-unit.log10().round()).max(0.0) as usize;
        let mut offset_text = format!("{:.*}", decimals, offset.abs());
        if offset_text.contains('.') {
            offset_text = offset_text
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string();
        }
        Axis {
            offset,
            offset_text,
            ..Axis::plain(lo - offset..hi - offset)
        }
    }

    fn plain(range: Range<f64>) -> Axis {
        let step = tick_step(range.start, range.end);
        let format = label_format(range.start, range.end, step);
        Axis {
            range,
            offset: 0.0,
            offset_text: String::new(),
            step,
            format,
        }
    }

    /// The label of the tick at `value`.
    pub fn label(&self, value: f64) -> String {
        // A tick at zero comes out of plotters' arithmetic as, say, -8e-28.
        let value = if value.abs() < 1e-6 * self.step {
            0.0
        } else {
            value
        };
        if value == 0.0 {
            return if let LabelFormat::Fixed(decimals) = self.format {
                format!("{:.decimals$}", 0.0)
            } else {
                "0".into()
            };
        }
        let text = match self.format {
            LabelFormat::Fixed(decimals) => format!("{value:.decimals$}"),
            LabelFormat::Scientific(decimals) => format!("{value:.decimals$e}"),
        };
        // No "-0.0" for a tick that is zero up to rounding.
        match text.strip_prefix('-') {
            Some(rest)
                if rest
                    .chars()
                    .take_while(|c| *c != 'e')
                    .all(|c| c == '0' || c == '.') =>
            {
                rest.to_string()
            }
            _ => text,
        }
    }

    /// The axis description for the quantity `name`, with the offset if there is one.
    pub fn description(&self, name: &str) -> String {
        match self.offset {
            o if o > 0.0 => format!("{name} − {}", self.offset_text),
            o if o < 0.0 => format!("{name} + {}", self.offset_text),
            _ => name.to_string(),
        }
    }
}

/// The step between plotters' labelled ticks over `lo..hi`: the smallest of 1, 2 and 5 times a
/// power of ten that gives at most `MAX_TICKS` ticks.
fn tick_step(lo: f64, hi: f64) -> f64 {
    let first = (hi - lo).log10().floor() as i32 - 2;
    for power in first..first + 6 {
        for factor in [1.0, 2.0, 5.0] {
            let step = factor * 10f64.powi(power);
            if (hi / step + 1e-9).floor() - (lo / step - 1e-9).ceil() + 1.0 <= MAX_TICKS {
                return step;
            }
        }
    }
    hi - lo
}

/// Enough decimals to tell the ticks apart; scientific notation for large or small magnitudes.
fn label_format(lo: f64, hi: f64, step: f64) -> LabelFormat {
    let magnitude = lo.abs().max(hi.abs());
    let (top, bottom) = (
        magnitude.log10().floor() as i32,
        (step.log10() + 1e-9).floor() as i32,
    );
    if !(1e-3..1e5).contains(&magnitude) {
        LabelFormat::Scientific((top - bottom).max(0) as usize)
    } else {
        LabelFormat::Fixed((-bottom).max(0) as usize)
    }
}
