//! Line charts as SVG files (plotters' SVG backend: no system libraries, text as `<text>`
//! elements that any browser renders).
//!
//! ```no_run
//! use admm_ta_bench::plot::{Chart, Scale, Series};
//! Chart::new("round latency", "agents", "µs")
//!     .x_scale(Scale::Log)
//!     .series(Series::new("ipc", vec![(2.0, 40.0), (10.0, 150.0)]))
//!     .write(std::path::Path::new("latency.svg"))
//!     .unwrap();
//! ```

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use std::path::Path;

/// Linear or logarithmic axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    Linear,
    Log,
}

/// Corner of the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
}

/// One line of a chart.
#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed (e.g. a p99 line next to its p50).
    pub dashed: bool,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            dashed: false,
        }
    }

    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// A chart: title, axes, lines and optional horizontal reference lines.
#[derive(Debug, Clone)]
pub struct Chart {
    title: String,
    x_label: String,
    y_label: String,
    x_scale: Scale,
    y_scale: Scale,
    series: Vec<Series>,
    references: Vec<(String, f64)>,
    /// Series of the same `group` share a colour (p50 and p99 of one transport).
    colour_by_prefix: bool,
    legend: Legend,
}

/// Failures of writing a chart.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("chart '{0}' has no finite points to draw")]
    Empty(String),
    #[error("cannot draw chart '{title}' into {path}: {message}")]
    Draw {
        title: String,
        path: String,
        message: String,
    },
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

impl Chart {
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            series: Vec::new(),
            references: Vec::new(),
            colour_by_prefix: false,
            legend: Legend::UpperLeft,
        }
    }

    /// Where the legend goes (default: upper left, where rising curves leave room).
    pub fn legend(mut self, position: Legend) -> Self {
        self.legend = position;
        self
    }

    pub fn x_scale(mut self, scale: Scale) -> Self {
        self.x_scale = scale;
        self
    }

    pub fn y_scale(mut self, scale: Scale) -> Self {
        self.y_scale = scale;
        self
    }

    pub fn series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// A horizontal line at `y` (e.g. the optimum).
    pub fn reference(mut self, name: impl Into<String>, y: f64) -> Self {
        self.references.push((name.into(), y));
        self
    }

    /// Series whose names share the text before the first space get one colour.
    pub fn colour_by_prefix(mut self) -> Self {
        self.colour_by_prefix = true;
        self
    }

    fn usable(&self, (x, y): (f64, f64)) -> bool {
        x.is_finite()
            && y.is_finite()
            && (self.x_scale == Scale::Linear || x > 0.0)
            && (self.y_scale == Scale::Linear || y > 0.0)
    }

    /// Writes the chart as an SVG file.
    pub fn write(&self, path: &Path) -> Result<(), PlotError> {
        let points: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .chain(self.references.iter().map(|&(_, y)| (f64::NAN, y)))
            .collect();
        let xs: Vec<f64> = points
            .iter()
            .map(|p| p.0)
            .filter(|x| x.is_finite() && (self.x_scale == Scale::Linear || *x > 0.0))
            .collect();
        let ys: Vec<f64> = points
            .iter()
            .map(|p| p.1)
            .filter(|y| y.is_finite() && (self.y_scale == Scale::Linear || *y > 0.0))
            .collect();
        if xs.is_empty() || ys.is_empty() {
            return Err(PlotError::Empty(self.title.clone()));
        }
        let range = |v: &[f64], scale: Scale| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            match scale {
                Scale::Log => {
                    let (lo, hi) = if hi > lo {
                        (lo, hi)
                    } else {
                        (lo / 2.0, hi * 2.0)
                    };
                    (lo / 1.25, hi * 1.25)
                }
                Scale::Linear => {
                    let pad = if hi > lo {
                        (hi - lo) * 0.05
                    } else {
                        lo.abs().max(1.0) * 0.1
                    };
                    (lo - pad, hi + pad)
                }
            }
        };
        let (x0, x1) = range(&xs, self.x_scale);
        let (y0, y1) = range(&ys, self.y_scale);
        let result = match (self.x_scale, self.y_scale) {
            (Scale::Linear, Scale::Linear) => self.draw(path, x0..x1, y0..y1),
            (Scale::Log, Scale::Linear) => self.draw(path, (x0..x1).log_scale(), y0..y1),
            (Scale::Linear, Scale::Log) => self.draw(path, x0..x1, (y0..y1).log_scale()),
            (Scale::Log, Scale::Log) => self.draw(path, (x0..x1).log_scale(), (y0..y1).log_scale()),
        };
        result.map_err(|message| PlotError::Draw {
            title: self.title.clone(),
            path: path.display().to_string(),
            message,
        })
    }

    fn colour(&self, k: usize) -> RGBColor {
        if !self.colour_by_prefix {
            return PALETTE[k % PALETTE.len()];
        }
        let prefix = |s: &Series| s.name.split(' ').next().unwrap_or("").to_string();
        let mut groups: Vec<String> = Vec::new();
        for s in &self.series {
            let p = prefix(s);
            if !groups.contains(&p) {
                groups.push(p);
            }
        }
        let g = groups
            .iter()
            .position(|p| *p == prefix(&self.series[k]))
            .unwrap_or(0);
        PALETTE[g % PALETTE.len()]
    }

    fn draw<X, Y>(&self, path: &Path, x: X, y: Y) -> Result<(), String>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let err = |e: &dyn std::fmt::Display| e.to_string();
        let root = SVGBackend::new(path, (960, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x, y)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_labels(8)
            .y_labels(8)
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| err(&e))?;
        for (k, s) in self.series.iter().enumerate() {
            let colour = self.colour(k);
            let points: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&p| self.usable(p))
                .collect();
            let style = colour.stroke_width(2);
            if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(points.clone(), 6, 4, style))
                    .map_err(|e| err(&e))?
                    .label(&s.name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 8, y)], colour.stroke_width(2))
                    });
            } else {
                chart
                    .draw_series(LineSeries::new(points.clone(), style))
                    .map_err(|e| err(&e))?
                    .label(&s.name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                    });
            }
            if points.len() <= 40 {
                chart
                    .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| err(&e))?;
            }
        }
        for (name, yv) in &self.references {
            let (xa, xb) = {
                let r = chart.x_range();
                (r.start, r.end)
            };
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(xa, *yv), (xb, *yv)],
                    10,
                    5,
                    BLACK.stroke_width(2),
                ))
                .map_err(|e| err(&e))?
                .label(name)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        }
        chart
            .configure_series_labels()
            .position(match self.legend {
                Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
                Legend::UpperRight => SeriesLabelPosition::UpperRight,
                Legend::LowerLeft => SeriesLabelPosition::LowerLeft,
                Legend::LowerRight => SeriesLabelPosition::LowerRight,
            })
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))
    }
}

/// An axis label: integers without decimals, very large or small values in scientific
/// notation, others with at most 3 decimals.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e6).contains(&a) {
        format!("{v:.0e}")
    } else if (v - v.round()).abs() < 1e-9 * a.max(1.0) {
        format!("{v:.0}")
    } else {
        let text = format!("{v:.3}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn ticks_are_short() {
        assert_eq!(super::tick(&10.0), "10");
        assert_eq!(super::tick(&0.25), "0.25");
        assert_eq!(super::tick(&1e-5), "1e-5");
        assert_eq!(super::tick(&2e6), "2e6");
        assert_eq!(super::tick(&0.0), "0");
    }

    use super::*;

    #[test]
    fn writes_an_svg_with_every_series_name_and_refuses_an_empty_chart() {
        let dir = std::env::temp_dir().join(format!("admm-ta-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.svg");
        Chart::new("t", "x", "y")
            .x_scale(Scale::Log)
            .y_scale(Scale::Log)
            .series(Series::new("ipc p50", vec![(1.0, 2.0), (10.0, 30.0)]))
            .series(Series::new("ipc p99", vec![(1.0, 4.0), (10.0, 60.0)]).dashed())
            .reference("optimum", 5.0)
            .colour_by_prefix()
            .write(&path)
            .unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        for name in ["ipc p50", "ipc p99", "optimum"] {
            assert!(svg.contains(name), "{name} missing");
        }
        let empty = Chart::new("e", "x", "y")
            .y_scale(Scale::Log)
            .series(Series::new("zero", vec![(1.0, 0.0)]));
        assert!(matches!(
            empty.write(&dir.join("e.svg")),
            Err(PlotError::Empty(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
