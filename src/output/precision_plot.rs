//! The work-precision plot of `lsdc precision`: the error in positions against the CPU time,
//! both on logarithmic axes, one curve per integrator through its settings.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::plot::{
    write_figure, Figure, PlotError, Render, CAPTION_SIZE, LABEL_SIZE, LINE_WIDTH, PALETTE,
};
use crate::studies::precision::{Measurement, Table};

/// Draws the table's error against CPU time to `path` (`.svg` or `.png`). Runs that failed or
/// whose error is zero (nothing to put on a logarithmic axis) are left out.
pub fn plot(table: &Table, path: &Path) -> Result<(), PlotError> {
    let curves = curves(&table.measurements);
    if curves.is_empty() {
        return Err(PlotError::NoOutputs);
    }
    write_figure(&WorkPrecision { curves }, path)
}

/// One integrator's points (CPU seconds, position error), in the order of its settings: a
/// timing disturbed by the machine shows as a kink rather than reordering the curve.
struct Curve {
    label: String,
    points: Vec<(f64, f64)>,
}

fn curves(measurements: &[Measurement]) -> Vec<Curve> {
    let mut curves: Vec<Curve> = Vec::new();
    for m in measurements {
        let point = (m.cpu_seconds_min, m.errors.position);
        let plottable = point.0 > 0.0 && point.1 > 0.0 && point.1.is_finite();
        if m.failure.is_some() || !plottable {
            continue;
        }
        match curves.iter_mut().find(|c| c.label == m.integrator) {
            Some(curve) => curve.points.push(point),
            None => curves.push(Curve {
                label: m.integrator.clone(),
                points: vec![point],
            }),
        }
    }
    curves
}

struct WorkPrecision {
    curves: Vec<Curve>,
}

impl WorkPrecision {
    /// Decades enclosing the values of one coordinate of the points.
    fn range(&self, coordinate: impl Fn(&(f64, f64)) -> f64) -> std::ops::Range<f64> {
        let values = self
            .curves
            .iter()
            .flat_map(|c| c.points.iter().map(&coordinate));
        let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        10f64.powf(lo.log10().floor())..10f64.powf(hi.log10().ceil().max(lo.log10().floor() + 1.0))
    }
}

impl Figure for WorkPrecision {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        render: Render,
    ) -> Result<(), PlotError>
    where
        DB::ErrorType: 'static,
    {
        let error = PlotError::drawing::<DB::ErrorType>;
        let px = |length: f64| render.px(length);
        root.fill(&WHITE).map_err(error)?;
        let mut chart = ChartBuilder::on(root)
            .caption("Work and precision", render.font(CAPTION_SIZE))
            .margin(px(16.0))
            .x_label_area_size(px(56.0))
            .y_label_area_size(px(96.0))
            .build_cartesian_2d(
                self.range(|p| p.0).log_scale(),
                self.range(|p| p.1).log_scale(),
            )
            .map_err(error)?;
        let label = |v: &f64| format!("{v:.0e}");
        chart
            .configure_mesh()
            .x_desc("CPU time (s), least of the repeats")
            .y_desc("largest position error")
            .x_label_formatter(&label)
            .y_label_formatter(&label)
            .label_style(render.font(LABEL_SIZE))
            .axis_desc_style(render.font(LABEL_SIZE))
            .axis_style(BLACK.stroke_width(px(1.0)))
            .bold_line_style(BLACK.mix(0.15).stroke_width(px(1.0)))
            .light_line_style(BLACK.mix(0.05).stroke_width(px(1.0)))
            .draw()
            .map_err(error)?;
        for (i, curve) in self.curves.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let style = colour.stroke_width(px(LINE_WIDTH));
            let points = curve.points.iter().copied();
            chart
                .draw_series(LineSeries::new(points.clone(), style))
                .map_err(error)?
                .label(curve.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + px(24.0) as i32, y)], style)
                });
            let marker = move |p| Circle::new(p, px(4.0), colour.filled());
            chart.draw_series(points.map(marker)).map_err(error)?;
        }
        chart
            .configure_series_labels()
            .label_font(render.font(LABEL_SIZE))
            .legend_area_size(px(36.0))
            .margin(px(12.0))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.3))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(error)?;
        Ok(())
    }
}
