//! A small layer over `plotters`: figures of one or more panels of line series, written as PNG
//! and SVG with a bundled font (DejaVu Sans, no system font needed).

use plotters::coord::Shift;
use plotters::prelude::*;
use std::error::Error;
use std::path::{Path, PathBuf};

mod cart;
use cart::draw_cart;

/// Result with a boxed error.
pub type Res<T> = Result<T, Box<dyn Error>>;

const FONT: &str = "sans-serif";

/// Registers the bundled font with plotters' `ab_glyph` text renderer (once).
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        for style in [FontStyle::Normal, FontStyle::Bold] {
            // The bundled TTF is valid, so this cannot fail.
            let _ = plotters::style::register_font(FONT, style, bytes);
        }
    });
}

/// Line style.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dash {
    /// Solid.
    Solid,
    /// Dashed.
    Dashed,
    /// Dotted.
    Dotted,
    /// Markers only.
    Markers,
}

/// One line series.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: Option<String>,
    pub pts: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub dash: Dash,
    pub width: u32,
    pub markers: bool,
}

/// Ten distinguishable colours (matplotlib's tab10).
pub const TAB10: [RGBColor; 10] = [
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

/// Colour `i` of [`TAB10`] (cycled).
pub fn color(i: usize) -> RGBColor {
    TAB10[i % TAB10.len()]
}

/// Grey for reference lines.
pub const GREY: RGBColor = RGBColor(110, 110, 110);

impl Series {
    /// A solid line.
    pub fn line(name: impl Into<String>, pts: Vec<(f64, f64)>, color: RGBColor) -> Self {
        let name = name.into();
        Series {
            name: (!name.is_empty()).then_some(name),
            pts,
            color,
            dash: Dash::Solid,
            width: 2,
            markers: false,
        }
    }
    /// Dashed.
    pub fn dashed(mut self) -> Self {
        self.dash = Dash::Dashed;
        self
    }
    /// Dotted.
    pub fn dotted(mut self) -> Self {
        self.dash = Dash::Dotted;
        self
    }
    /// With a given dash.
    pub fn with_dash(mut self, d: Dash) -> Self {
        self.dash = d;
        self
    }
    /// Markers on the points (in addition to the line, unless the dash is [`Dash::Markers`]).
    pub fn markers(mut self) -> Self {
        self.markers = true;
        self
    }
    /// Markers only.
    pub fn points_only(mut self) -> Self {
        self.dash = Dash::Markers;
        self.markers = true;
        self
    }
    /// Line width.
    pub fn width(mut self, w: u32) -> Self {
        self.width = w;
        self
    }
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Legend {
    None,
    UpperRight,
    UpperLeft,
    LowerRight,
    LowerLeft,
    /// Outside the plot, right.
    Right,
}

/// One panel (a Cartesian chart).
#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub x: String,
    pub y: String,
    pub series: Vec<Series>,
    pub logx: bool,
    pub logy: bool,
    pub xr: Option<(f64, f64)>,
    pub yr: Option<(f64, f64)>,
    pub legend: Legend,
    /// Equal scales on both axes (beam configurations).
    pub equal: bool,
    /// A colour map drawn under the series, with a colour bar at the right.
    pub heat: Option<Heat>,
    /// Set by [`draw_panel`]: the axis holds log₁₀ values, labelled as powers of ten (plotters'
    /// log axes drop every label below 2.2·10⁻¹⁶, so deep log ranges are drawn this way).
    pub exp_x: bool,
    pub exp_y: bool,
}

/// Values on a regular grid, drawn as coloured cells (viridis) under a panel's series.
#[derive(Clone, Debug)]
pub struct Heat {
    /// x range of the grid (cell centres at the ends).
    pub x: (f64, f64),
    /// y range of the grid.
    pub y: (f64, f64),
    /// Points along x and y.
    pub nx: usize,
    pub ny: usize,
    /// Values, x varying slowest: `values[i * ny + j]` at (x_i, y_j).
    pub values: Vec<f64>,
    /// Colour by log₁₀ of the value (non-positive values get the lowest colour).
    pub log: bool,
    /// Lower clip of the colour scale (log scale: values below it get the lowest colour).
    pub floor: Option<f64>,
    /// Colour bar label.
    pub label: String,
}

/// Viridis, by linear interpolation between 9 anchors; `t` in [0, 1].
pub fn viridis(t: f64) -> RGBColor {
    const A: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (A.len() - 1) as f64;
    let i = (x.floor() as usize).min(A.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        mix(A[i].0, A[i + 1].0),
        mix(A[i].1, A[i + 1].1),
        mix(A[i].2, A[i + 1].2),
    )
}

impl Heat {
    /// The colour-scale range (in log₁₀ units for a log scale).
    fn range(&self) -> (f64, f64) {
        let tr = |v: f64| self.scaled(v);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for &v in &self.values {
            let t = tr(v);
            if t.is_finite() {
                lo = lo.min(t);
                hi = hi.max(t);
            }
        }
        if let Some(f) = self.floor {
            lo = lo.max(if self.log { f.log10() } else { f });
        }
        if !lo.is_finite() || hi <= lo {
            (lo.min(0.0), lo.min(0.0) + 1.0)
        } else {
            (lo, hi)
        }
    }
    fn scaled(&self, v: f64) -> f64 {
        if self.log {
            if v > 0.0 {
                v.log10()
            } else {
                f64::NEG_INFINITY
            }
        } else {
            v
        }
    }
    fn color(&self, v: f64, (lo, hi): (f64, f64)) -> RGBColor {
        if v.is_nan() {
            // no value (e.g. the simulation failed there)
            return RGBColor(225, 225, 225);
        }
        let t = self.scaled(v);
        if t == f64::NEG_INFINITY {
            return viridis(0.0);
        }
        viridis((t - lo) / (hi - lo))
    }
    /// The n + 1 cell edges around n centres spaced evenly over `r` (geometrically on a log
    /// axis).
    fn edges(r: (f64, f64), n: usize, log: bool) -> Vec<f64> {
        let (a, b) = if log { (r.0.ln(), r.1.ln()) } else { r };
        let d = if n > 1 { (b - a) / (n - 1) as f64 } else { 1.0 };
        (0..=n)
            .map(|i| {
                let e = a + (i as f64 - 0.5) * d;
                if log {
                    e.exp()
                } else {
                    e
                }
            })
            .collect()
    }
}

impl Panel {
    /// A linear panel.
    pub fn new(title: impl Into<String>, x: impl Into<String>, y: impl Into<String>) -> Self {
        Panel {
            title: title.into(),
            x: x.into(),
            y: y.into(),
            series: Vec::new(),
            logx: false,
            logy: false,
            xr: None,
            yr: None,
            legend: Legend::UpperRight,
            equal: false,
            heat: None,
            exp_x: false,
            exp_y: false,
        }
    }
    /// With a colour map under the series.
    pub fn heat(mut self, h: Heat) -> Self {
        self.heat = Some(h);
        self
    }
    /// Log-log.
    pub fn loglog(mut self) -> Self {
        self.logx = true;
        self.logy = true;
        self
    }
    /// Log y.
    pub fn logy(mut self) -> Self {
        self.logy = true;
        self
    }
    /// Legend position.
    pub fn legend(mut self, l: Legend) -> Self {
        self.legend = l;
        self
    }
    /// Fixed x range.
    pub fn xr(mut self, a: f64, b: f64) -> Self {
        self.xr = Some((a, b));
        self
    }
    /// Fixed y range.
    pub fn yr(mut self, a: f64, b: f64) -> Self {
        self.yr = Some((a, b));
        self
    }
    /// Adds a series.
    pub fn push(&mut self, s: Series) {
        self.series.push(s);
    }
    /// Adds a series (builder).
    pub fn with(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }
}

/// A figure: panels on a grid.
#[derive(Clone, Debug)]
pub struct Figure {
    /// File stem, e.g. `fig_2_5`.
    pub name: String,
    pub panels: Vec<Panel>,
    pub cols: usize,
    /// Size of one panel in pixels at scale 1.
    pub panel_size: (u32, u32),
}

impl Figure {
    /// A figure with panels laid out in `cols` columns.
    pub fn new(name: impl Into<String>, cols: usize, panels: Vec<Panel>) -> Self {
        Figure {
            name: name.into(),
            panels,
            cols: cols.max(1),
            panel_size: (800, 560),
        }
    }
    /// A one-panel figure.
    pub fn single(name: impl Into<String>, panel: Panel) -> Self {
        Self::new(name, 1, vec![panel])
    }
}

fn data_range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for v in vals {
        if v.is_finite() && (!log || v > 0.0) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return if log { (1e-3, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let pad = ((b - a) * 0.05).max(0.1);
        (10f64.powf(a - pad), 10f64.powf(b + pad))
    } else {
        let span = hi - lo;
        let pad = if span > 0.0 {
            span * 0.05
        } else {
            lo.abs().max(1.0) * 0.05
        };
        (lo - pad, hi + pad)
    }
}

/// Number formatting for tick labels.
pub fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let e = a.log10().floor() as i32;
        let m = v / 10f64.powi(e);
        if (m.abs() - 1.0).abs() < 1e-6 {
            format!("{}1e{e}", if v < 0.0 { "-" } else { "" })
        } else if (m - m.round()).abs() < 1e-6 {
            format!("{}e{e}", m.round() as i64)
        } else {
            format!("{m:.1}e{e}")
        }
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    }
}

fn panel_ranges(p: &Panel) -> ((f64, f64), (f64, f64)) {
    if let Some(h) = &p.heat {
        let ex = Heat::edges(h.x, h.nx, p.logx);
        let ey = Heat::edges(h.y, h.ny, p.logy);
        return (
            p.xr.unwrap_or((ex[0], ex[h.nx])),
            p.yr.unwrap_or((ey[0], ey[h.ny])),
        );
    }
    let mut xr = p.xr.unwrap_or_else(|| {
        data_range(
            p.series.iter().flat_map(|s| s.pts.iter().map(|q| q.0)),
            p.logx,
        )
    });
    let mut yr = p.yr.unwrap_or_else(|| {
        data_range(
            p.series.iter().flat_map(|s| s.pts.iter().map(|q| q.1)),
            p.logy,
        )
    });
    if p.equal && !p.logx && !p.logy {
        // widen the smaller span so both axes have the same scale (panel aspect ~ 1.43)
        let aspect = 1.43;
        let (sx, sy) = (xr.1 - xr.0, yr.1 - yr.0);
        if sx / aspect > sy {
            let c = 0.5 * (yr.0 + yr.1);
            yr = (c - 0.5 * sx / aspect, c + 0.5 * sx / aspect);
        } else {
            let c = 0.5 * (xr.0 + xr.1);
            xr = (c - 0.5 * sy * aspect, c + 0.5 * sy * aspect);
        }
    }
    (xr, yr)
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel, s: f64) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let ((x0, x1), (y0, y1)) = panel_ranges(p);
    // log axes reaching below 1e-15 are redrawn as linear axes of log₁₀ values
    let deep = |log: bool, a: f64| log && a < 1e-15;
    if deep(p.logx, x0) || deep(p.logy, y0) {
        let (tx, ty) = (deep(p.logx, x0), deep(p.logy, y0));
        let mut q = p.clone();
        let f = |t: bool, v: f64| if t { v.log10() } else { v };
        for ser in q.series.iter_mut() {
            ser.pts = ser
                .pts
                .iter()
                .filter(|r| (!tx || r.0 > 0.0) && (!ty || r.1 > 0.0))
                .map(|r| (f(tx, r.0), f(ty, r.1)))
                .collect();
        }
        q.xr = Some((f(tx, x0), f(tx, x1)));
        q.yr = Some((f(ty, y0), f(ty, y1)));
        q.logx &= !tx;
        q.logy &= !ty;
        q.exp_x = tx;
        q.exp_y = ty;
        return draw_panel(area, &q, s);
    }
    let area = &if let Some(h) = &p.heat {
        let w = area.dim_in_pixel().0 as i32;
        let bar = ((120.0 * s).round() as i32).min(w / 3);
        let (main, right) = area.split_horizontally(w - bar);
        draw_colorbar(&right, h, s)?;
        main
    } else {
        area.clone()
    };
    let lx = || {
        let (bold, light) = log_ticks(x0, x1);
        (x0..x1)
            .log_scale()
            .with_key_points(bold)
            .with_light_points(light)
    };
    let ly = || {
        let (bold, light) = log_ticks(y0, y1);
        (y0..y1)
            .log_scale()
            .with_key_points(bold)
            .with_light_points(light)
    };
    match (p.logx, p.logy) {
        (false, false) => draw_cart(area, p, s, x0..x1, y0..y1),
        (true, false) => draw_cart(area, p, s, lx(), y0..y1),
        (false, true) => draw_cart(area, p, s, x0..x1, ly()),
        (true, true) => draw_cart(area, p, s, lx(), ly()),
    }
}

/// Labelled and light tick positions of a log axis on [a, b]: mantissas 1, 2, 3, 5, 7 per decade
/// over at most 1.5 decades, 1, 2, 5 up to 3, powers of ten up to 8, every n-th power beyond
/// (plotters' own log ticks label nothing but powers of ten).
fn log_ticks(a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    let (lo, hi) = (a.min(b), a.max(b));
    if !(lo > 0.0 && hi.is_finite()) {
        return (Vec::new(), Vec::new());
    }
    let decades = (hi / lo).log10();
    let (e0, e1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let inside = |v: &f64| *v >= lo * (1.0 - 1e-12) && *v <= hi * (1.0 + 1e-12);
    let with = |m: &[f64], step: i32| -> Vec<f64> {
        (e0..=e1)
            .filter(|e| e.rem_euclid(step) == 0)
            .flat_map(|e| m.iter().map(move |x| x * 10f64.powi(e)))
            .filter(inside)
            .collect()
    };
    let bold = if decades <= 1.5 {
        with(&[1.0, 2.0, 3.0, 5.0, 7.0], 1)
    } else if decades <= 3.0 {
        with(&[1.0, 2.0, 5.0], 1)
    } else if decades <= 8.0 {
        with(&[1.0], 1)
    } else {
        with(&[1.0], (decades / 7.0).ceil() as i32)
    };
    let light = if decades <= 8.0 {
        with(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1)
    } else {
        with(&[1.0], 1)
    };
    (bold, light)
}

fn draw_colorbar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, h: &Heat, s: f64) -> Res<()>
where
    DB::ErrorType: 'static,
{
    let px = |v: f64| ((v * s).round() as i32).max(1);
    let (lo, hi) = h.range();
    let cells = 100;
    if h.log && 10f64.powf(lo) > 1e-15 {
        // a real log axis with 1-2-5 labels (log_ticks)
        let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
        let (bold, light) = log_ticks(a, b);
        let mut chart = ChartBuilder::on(area)
            .margin_top(px(46.0))
            .margin_bottom(px(67.0))
            .margin_right(px(8.0))
            .y_label_area_size(px(62.0))
            .build_cartesian_2d(
                0.0..1.0,
                (a..b)
                    .log_scale()
                    .with_key_points(bold)
                    .with_light_points(light),
            )?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .disable_y_mesh()
            .disable_x_axis()
            .y_desc(h.label.as_str())
            .y_label_formatter(&|v: &f64| fmt_tick(*v))
            .label_style((FONT, px(13.0)))
            .axis_desc_style((FONT, px(15.0)))
            .draw()?;
        chart.draw_series((0..cells).map(|i| {
            let e0 = lo + (hi - lo) * i as f64 / cells as f64;
            let e1 = lo + (hi - lo) * (i + 1) as f64 / cells as f64;
            let c = viridis((i as f64 + 0.5) / cells as f64);
            Rectangle::new([(0.0, 10f64.powf(e0)), (1.0, 10f64.powf(e1))], c.filled())
        }))?;
        return Ok(());
    }
    let mut chart = ChartBuilder::on(area)
        .margin_top(px(46.0))
        .margin_bottom(px(67.0))
        .margin_right(px(8.0))
        .y_label_area_size(px(62.0))
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    let log = h.log;
    let fy = move |v: &f64| {
        if !log {
            fmt_tick(*v)
        } else if (v - v.round()).abs() < 1e-9 {
            format!("1e{}", v.round() as i64)
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_desc(h.label.as_str())
        .y_label_formatter(&fy)
        .label_style((FONT, px(13.0)))
        .axis_desc_style((FONT, px(15.0)))
        .y_labels(6)
        .draw()?;
    chart.draw_series((0..cells).map(|i| {
        let a = lo + (hi - lo) * i as f64 / cells as f64;
        let b = lo + (hi - lo) * (i + 1) as f64 / cells as f64;
        let c = viridis((i as f64 + 0.5) / cells as f64);
        Rectangle::new([(0.0, a), (1.0, b)], c.filled())
    }))?;
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure, s: f64) -> Res<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let rows = fig.panels.len().div_ceil(fig.cols);
    let areas = root.split_evenly((rows, fig.cols));
    for (a, p) in areas.iter().zip(fig.panels.iter()) {
        draw_panel(a, p, s)?;
    }
    root.present()?;
    Ok(())
}

/// Writes `out/NAME.png` and `out/NAME.svg`; `scale` scales the pixel size (1 = full size).
pub fn save(fig: &Figure, out: &Path, scale: f64) -> Res<Vec<PathBuf>> {
    register_font();
    let rows = fig.panels.len().div_ceil(fig.cols) as u32;
    let w = ((fig.panel_size.0 * fig.cols as u32) as f64 * scale).round() as u32;
    let h = ((fig.panel_size.1 * rows) as f64 * scale).round() as u32;
    let png = out.join(format!("{}.png", fig.name));
    let svg = out.join(format!("{}.svg", fig.name));
    draw_figure(
        BitMapBackend::new(&png, (w, h)).into_drawing_area(),
        fig,
        scale,
    )?;
    draw_figure(
        SVGBackend::new(&svg, (w, h)).into_drawing_area(),
        fig,
        scale,
    )?;
    Ok(vec![png, svg])
}
