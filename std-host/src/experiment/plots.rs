//! Charts as SVG and PNG with `plotters`, without system font libraries: text is drawn with
//! `ab_glyph` from DejaVu Sans, bundled in the binary (the `dejavu` crate; the fonts' own licence
//! is the Bitstream Vera one), so charts keep their titles, axes and legends on a machine with no
//! fonts at all. `RDBVH_FONT=path` draws with another TTF; `RDBVH_FONT=` (empty) draws no text.

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::ExperimentError;

const SIZE: (u32, u32) = (960, 540);

/// Registers the charts' font once; true when charts have text (false only for an empty
/// `RDBVH_FONT`). A `RDBVH_FONT` that cannot be read or parsed falls back to the bundled font.
pub fn fonts_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        let from_env = std::env::var_os("RDBVH_FONT");
        if from_env.as_deref().is_some_and(|p| p.is_empty()) {
            return false;
        }
        if let Some(bytes) = from_env.and_then(|path| std::fs::read(path).ok()) {
            // The font table wants 'static bytes; one font for the process's life.
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                return true;
            }
        }
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .is_ok()
    })
}

/// A grouped bar chart: one group of bars per category, one bar per series (`None` is no bar).
#[derive(Clone, Debug)]
pub struct Bars<'a> {
    /// Title.
    pub title: &'a str,
    /// Y axis description.
    pub y_label: &'a str,
    /// Category names.
    pub categories: &'a [String],
    /// Series: name, colour (an index into `plotters`' `Palette99`, so a series keeps its colour
    /// whichever others are drawn) and values.
    pub series: Vec<(String, usize, Vec<Option<f64>>)>,
    /// A horizontal reference line (such as 1 for ratios).
    pub reference: Option<f64>,
}

/// A line chart.
#[derive(Clone, Debug)]
pub struct Lines<'a> {
    /// Title.
    pub title: &'a str,
    /// X axis description.
    pub x_label: &'a str,
    /// Y axis description.
    pub y_label: &'a str,
    /// Series names and points.
    pub series: Vec<(String, Vec<(f64, f64)>)>,
}

/// A chart that can draw itself on any backend.
pub trait Chart {
    /// Draws on `root`; `text` says whether a font is available.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        text: bool,
    ) -> Result<(), String>;
}

fn e<E: std::fmt::Debug>(x: E) -> String {
    format!("{x:?}")
}

impl Chart for Bars<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        text: bool,
    ) -> Result<(), String> {
        root.fill(&WHITE).map_err(e)?;
        let n = self.categories.len().max(1);
        let ymax = self
            .series
            .iter()
            .flat_map(|(_, _, v)| v.iter().flatten())
            .copied()
            .chain(self.reference)
            .fold(0.0f64, f64::max)
            .max(1e-9)
            // Head room for the legend in the upper right, a line per series, above the bars.
            * (1.15 + 0.09 * self.series.len() as f64);
        let mut b = ChartBuilder::on(root);
        b.margin(12);
        if text {
            b.caption(self.title, ("sans-serif", 22))
                .x_label_area_size(36)
                .y_label_area_size(64);
        }
        let mut chart = b
            .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), 0f64..ymax)
            .map_err(e)?;
        let cats = self.categories;
        let fmt = |x: &f64| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < cats.len() {
                cats[i as usize].clone()
            } else {
                String::new()
            }
        };
        let mut mesh = chart.configure_mesh();
        mesh.disable_x_mesh();
        if text {
            mesh.x_labels(n + 1)
                .x_label_formatter(&fmt)
                .y_desc(self.y_label);
        } else {
            mesh.x_labels(0).y_labels(0);
        }
        mesh.draw().map_err(e)?;
        let k = self.series.len().max(1) as f64;
        let w = 0.8 / k;
        for (s, (name, colour, vals)) in self.series.iter().enumerate() {
            let color = Palette99::pick(*colour).to_rgba();
            let bars = vals.iter().enumerate().filter_map(move |(i, v)| {
                v.map(|v| {
                    let x0 = i as f64 - 0.4 + s as f64 * w;
                    Rectangle::new([(x0, 0.0), (x0 + w * 0.95, v)], color.filled())
                })
            });
            let drawn = chart.draw_series(bars).map_err(e)?;
            if text {
                drawn.label(name.as_str()).legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], color.filled())
                });
            }
        }
        if let Some(r) = self.reference {
            chart
                .draw_series(LineSeries::new(
                    [(-0.5, r), (n as f64 - 0.5, r)],
                    BLACK.stroke_width(1),
                ))
                .map_err(e)?;
        }
        if text && !self.series.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(e)?;
        }
        root.present().map_err(e)
    }
}

impl Chart for Lines<'_> {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        text: bool,
    ) -> Result<(), String> {
        root.fill(&WHITE).map_err(e)?;
        let pts = || self.series.iter().flat_map(|(_, p)| p.iter());
        let (x0, x1) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
        let (x0, x1) = if x0.is_finite() && x1 > x0 {
            (x0, x1)
        } else {
            (0.0, 1.0)
        };
        let ymax = pts().map(|p| p.1).fold(0.0f64, f64::max).max(1e-9) * 1.1;
        let mut b = ChartBuilder::on(root);
        b.margin(12);
        if text {
            b.caption(self.title, ("sans-serif", 22))
                .x_label_area_size(40)
                .y_label_area_size(64);
        }
        let mut chart = b.build_cartesian_2d(x0..x1, 0f64..ymax).map_err(e)?;
        let mut mesh = chart.configure_mesh();
        // Whole-number ticks (levels, area counts) read as integers, not `1.0, 2.0`.
        let x_fmt = |x: &f64| {
            if x.fract() == 0.0 {
                format!("{x:.0}")
            } else {
                format!("{x}")
            }
        };
        if text {
            mesh.x_desc(self.x_label)
                .y_desc(self.y_label)
                .x_label_formatter(&x_fmt);
        } else {
            mesh.x_labels(0).y_labels(0);
        }
        mesh.draw().map_err(e)?;
        for (s, (name, p)) in self.series.iter().enumerate() {
            let color = Palette99::pick(s).to_rgba();
            let drawn = chart
                .draw_series(LineSeries::new(p.iter().copied(), color.stroke_width(2)))
                .map_err(e)?;
            if text {
                drawn.label(name.as_str()).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 14, y)], color.stroke_width(2))
                });
            }
            chart
                .draw_series(p.iter().map(|&q| Circle::new(q, 3, color.filled())))
                .map_err(e)?;
        }
        if text && !self.series.is_empty() {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(e)?;
        }
        root.present().map_err(e)
    }
}

/// Draws `chart` to `dir/stem.svg` and `dir/stem.png`.
pub fn save(chart: &impl Chart, dir: &Path, stem: &str) -> Result<(), ExperimentError> {
    let text = fonts_available();
    let svg = dir.join(format!("{stem}.svg"));
    let png = dir.join(format!("{stem}.png"));
    {
        let root = SVGBackend::new(&svg, SIZE).into_drawing_area();
        chart
            .draw(&root, text)
            .map_err(|m| ExperimentError::Plot(format!("{}: {m}", svg.display())))?;
    }
    let root = BitMapBackend::new(&png, SIZE).into_drawing_area();
    chart
        .draw(&root, text)
        .map_err(|m| ExperimentError::Plot(format!("{}: {m}", png.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chart drawn into an RGB buffer, with or without text.
    fn pixels(text: bool) -> Vec<u8> {
        let categories = vec!["a".to_string(), "b".to_string()];
        let chart = Bars {
            title: "Bundled font title",
            y_label: "cost",
            categories: &categories,
            series: vec![("s".to_string(), 0, vec![Some(1.0), Some(2.0)])],
            reference: Some(1.0),
        };
        let mut buffer = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buffer, SIZE).into_drawing_area();
            chart.draw(&root, text).unwrap();
            root.present().unwrap();
        }
        buffer
    }

    #[test]
    fn charts_draw_their_title_with_the_bundled_font() {
        // The bundled font is registered whatever the machine has; RDBVH_FONT is unset under
        // `cargo test` unless a user sets it, and then it must be a font too.
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .map_err(|_| "the bundled font does not parse")
            .unwrap();
        let (with, without) = (pixels(true), pixels(false));
        // The title band (the top 40 rows) differs in many pixels: glyphs were drawn.
        let band = (SIZE.0 * 40 * 3) as usize;
        let differing = with[..band]
            .iter()
            .zip(&without[..band])
            .filter(|(a, b)| a != b)
            .count();
        assert!(differing > 300, "only {differing} title-band bytes differ");
    }
}
