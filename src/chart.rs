//! Error-against-time charts (log-log), drawn once with plotters and
//! written both as SVG and as PNG. Text is laid out with the bundled DejaVu
//! Sans (assets/fonts) through plotters' `ab_glyph` feature, so no system
//! font library is needed.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// One curve: a label and its (seconds, error) points, in render order.
#[derive(Clone, Debug)]
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// What the chart shows.
#[derive(Clone, Debug)]
pub struct ChartSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub curves: Vec<Curve>,
    /// Draw a dashed 1/x guide through each curve's first point (the rate
    /// of an unbiased Monte Carlo estimator).
    pub guides: bool,
}

pub const WIDTH: u32 = 960;
pub const HEIGHT: u32 = 640;
pub(crate) const FONT: &str = "glint-sans";

#[derive(Debug, thiserror::Error)]
#[error("chart: {0}")]
pub struct ChartError(pub(crate) String);

fn err(e: impl std::fmt::Display) -> ChartError {
    ChartError(e.to_string())
}

pub(crate) fn register_font() -> Result<(), ChartError> {
    static ONCE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *ONCE.get_or_init(|| {
        plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            include_bytes!("../assets/fonts/DejaVuSans.ttf"),
        )
        .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(ChartError("the bundled font does not load".into()))
    }
}

/// A palette that stays apart on white (Tableau 10).
const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Range of the positive, finite values, padded by a factor on each side.
fn log_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in vals.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi > 0.0) {
        return (0.1, 10.0);
    }
    if hi / lo < 10.0 {
        let mid = (hi * lo).sqrt();
        return (mid / 4.0, mid * 4.0);
    }
    (lo / 1.5, hi * 1.5)
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &ChartSpec,
) -> Result<(), ChartError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let xs = spec
        .curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.0));
    let ys = spec
        .curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.1));
    let (x0, x1) = log_range(xs);
    let (y0, y1) = log_range(ys);
    let mut chart = ChartBuilder::on(&root)
        .caption(&spec.title, (FONT, 20))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&spec.x_label)
        .y_desc(&spec.y_label)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .draw()
        .map_err(err)?;
    for (i, c) in spec.curves.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = c
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && *x > 0.0 && y.is_finite() && *y > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(err)?
            .label(c.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?;
        if spec.guides
            && let Some(&(t0, e0)) = pts.first()
        {
            // e(t) = e0 t0 / t across the chart's x range.
            let guide = [x0, x1].map(|t| (t, e0 * t0 / t));
            chart
                .draw_series(DashedLineSeries::new(
                    guide,
                    6,
                    4,
                    color.mix(0.6).stroke_width(1),
                ))
                .map_err(err)?;
        }
    }
    if spec.guides {
        // A legend entry that says what the dashed lines are.
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label("dashed: 1/t through each first point")
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.6).stroke_width(1))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// The chart as an SVG document.
pub fn svg(spec: &ChartSpec) -> Result<String, ChartError> {
    register_font()?;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (WIDTH, HEIGHT)).into_drawing_area();
        draw(root, spec)?;
    }
    Ok(s)
}

/// The same drawing rasterised: RGB8 pixels, `WIDTH` x `HEIGHT`.
pub fn rgb(spec: &ChartSpec) -> Result<Vec<u8>, ChartError> {
    register_font()?;
    let mut buf = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        draw(root, spec)?;
    }
    Ok(buf)
}

/// The same drawing as PNG bytes.
pub fn png(spec: &ChartSpec) -> Result<Vec<u8>, ChartError> {
    let buf = rgb(spec)?;
    let img = image::RgbImage::from_raw(WIDTH, HEIGHT, buf).expect("sized buffer");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(err)?;
    Ok(out.into_inner())
}

/// A pass/degrade/fail map over a parameter grid (`glint stability`).
#[derive(Clone, Debug)]
pub struct Heatmap {
    pub title: String,
    /// Row labels (the family's parameter values), top to bottom.
    pub rows: Vec<String>,
    pub cols: usize,
    /// (row, col, status 0 pass / 1 degrade / 2 fail, largest error).
    pub cells: Vec<(usize, usize, u8, f64)>,
}

/// Panels per row of the heat-map figure.
const MAP_COLUMNS: usize = 4;
const MAP_PANEL_W: u32 = 330;
const MAP_PANEL_H: u32 = 260;

/// A cell's colour: green (pass), amber (degrade), red (fail); a passing
/// cell is paler the smaller its error (log10 from 1e-6 to 1e-2).
fn cell_color(status: u8, err: f64) -> RGBColor {
    match status {
        0 => {
            let t = ((err.max(1e-9).log10() + 6.0) / 4.0).clamp(0.0, 1.0);
            let l = |a: f64, b: f64| (a + (b - a) * t) as u8;
            RGBColor(l(222.0, 120.0), l(245.0, 200.0), l(222.0, 120.0))
        }
        1 => RGBColor(245, 176, 65),
        _ => RGBColor(214, 39, 40),
    }
}

fn draw_maps<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    legend: &str,
    maps: &[Heatmap],
) -> Result<(), ChartError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let (root_title, body) = root.split_vertically(60);
    root_title
        .draw(&Text::new(
            title.to_string(),
            (16, 10),
            (FONT, 20).into_font().color(&BLACK),
        ))
        .map_err(err)?;
    root_title
        .draw(&Text::new(
            legend.to_string(),
            (16, 36),
            (FONT, 12).into_font().color(&BLACK),
        ))
        .map_err(err)?;
    let rows = maps.len().div_ceil(MAP_COLUMNS).max(1);
    let panels = body.split_evenly((rows, MAP_COLUMNS));
    for (panel, map) in panels.iter().zip(maps) {
        panel
            .draw(&Text::new(
                map.title.clone(),
                (8, 4),
                (FONT, 13).into_font().color(&BLACK),
            ))
            .map_err(err)?;
        let (x0, y0) = (96i32, 24i32);
        let (w, h) = panel.dim_in_pixel();
        let cw = ((w as i32 - x0 - 8) / map.cols.max(1) as i32).max(1);
        let ch = ((h as i32 - y0 - 8) / map.rows.len().max(1) as i32).clamp(1, 24);
        for (r, label) in map.rows.iter().enumerate() {
            panel
                .draw(&Text::new(
                    label.clone(),
                    (4, y0 + r as i32 * ch + ch / 2 - 6),
                    (FONT, 11).into_font().color(&BLACK),
                ))
                .map_err(err)?;
        }
        for &(r, c, status, e) in &map.cells {
            let (cx, cy) = (x0 + c as i32 * cw, y0 + r as i32 * ch);
            panel
                .draw(&Rectangle::new(
                    [(cx, cy), (cx + cw - 1, cy + ch - 1)],
                    cell_color(status, e).filled(),
                ))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

fn maps_size(maps: &[Heatmap]) -> (u32, u32) {
    let rows = maps.len().div_ceil(MAP_COLUMNS).max(1) as u32;
    (MAP_COLUMNS as u32 * MAP_PANEL_W, 60 + rows * MAP_PANEL_H)
}

/// The heat maps as an SVG document; `legend` is the line under the title.
pub fn heatmaps_svg(title: &str, legend: &str, maps: &[Heatmap]) -> Result<String, ChartError> {
    register_font()?;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, maps_size(maps)).into_drawing_area();
        draw_maps(root, title, legend, maps)?;
    }
    Ok(s)
}

/// The heat maps as PNG bytes.
pub fn heatmaps_png(title: &str, legend: &str, maps: &[Heatmap]) -> Result<Vec<u8>, ChartError> {
    register_font()?;
    let (w, h) = maps_size(maps);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        draw_maps(root, title, legend, maps)?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).expect("sized buffer");
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(err)?;
    Ok(out.into_inner())
}
