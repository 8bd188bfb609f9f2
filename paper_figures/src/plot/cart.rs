//! One Cartesian panel of a figure: its axes, heat map, series and legend.

use super::{fmt_tick, panel_ranges, Dash, Heat, Legend, Panel, Res, Series, FONT};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

/// A length of `v` pixels at scale `s` (at least 1).
fn px_at(v: f64, s: f64) -> i32 {
    ((v * s).round() as i32).max(1)
}

/// One Cartesian panel: axes, the heat map (if any), the series, the legend.
pub(super) fn draw_cart<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    s: f64,
    xs: X,
    ys: Y,
) -> Res<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let px = |v: f64| px_at(v, s);
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, (FONT, px(22.0)))
        .margin(px(12.0))
        .x_label_area_size(px(55.0))
        .y_label_area_size(px(85.0))
        .build_cartesian_2d(xs, ys)?;
    draw_axes(&mut chart, p, s)?;
    if let Some(h) = &p.heat {
        draw_heat(&mut chart, p, h)?;
    }
    for ser in &p.series {
        draw_line(&mut chart, p, ser, s)?;
    }
    draw_legend(&mut chart, p, s)
}

/// A panel's chart of x and y coordinates `XC`, `YC`.
type Chart<'a, DB, XC, YC> = ChartContext<'a, DB, Cartesian2d<XC, YC>>;

/// The axes, their labels and the grid; linear axes print round-off around zero as 0,
/// exponent axes (`exp_x`, `exp_y`) label whole exponents `1eK`.
fn draw_axes<'a, DB, XC, YC>(chart: &mut Chart<'a, DB, XC, YC>, p: &Panel, s: f64) -> Res<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    XC: Ranged<ValueType = f64> + ValueFormatter<f64>,
    YC: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let px = |v: f64| px_at(v, s);
    let ((xa, xb), (ya, yb)) = panel_ranges(p);
    let (xz, yz) = (
        if p.logx { 0.0 } else { 1e-9 * (xb - xa).abs() },
        if p.logy { 0.0 } else { 1e-9 * (yb - ya).abs() },
    );
    let exp_label = |v: f64| {
        if (v - v.round()).abs() < 1e-9 {
            format!("1e{}", v.round() as i64)
        } else {
            String::new()
        }
    };
    let (ex, ey) = (p.exp_x, p.exp_y);
    let fx = move |v: &f64| {
        if ex {
            exp_label(*v)
        } else {
            fmt_tick(if v.abs() < xz { 0.0 } else { *v })
        }
    };
    let fy = move |v: &f64| {
        if ey {
            exp_label(*v)
        } else {
            fmt_tick(if v.abs() < yz { 0.0 } else { *v })
        }
    };
    chart
        .configure_mesh()
        .x_desc(p.x.as_str())
        .y_desc(p.y.as_str())
        .label_style((FONT, px(15.0)))
        .axis_desc_style((FONT, px(17.0)))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_labels(7)
        .y_labels(7)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()?;
    Ok(())
}

/// The heat map's cells.
fn draw_heat<'a, DB, XC, YC>(chart: &mut Chart<'a, DB, XC, YC>, p: &Panel, h: &Heat) -> Res<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    XC: Ranged<ValueType = f64>,
    YC: Ranged<ValueType = f64>,
{
    let ex = Heat::edges(h.x, h.nx, p.logx);
    let ey = Heat::edges(h.y, h.ny, p.logy);
    let r = h.range();
    let (ex, ey) = (&ex, &ey);
    chart.draw_series((0..h.nx).flat_map(|i| {
        (0..h.ny).map(move |j| {
            let c = h.color(h.values[i * h.ny + j], r);
            Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], c.filled())
        })
    }))?;
    Ok(())
}

/// One series: its line (solid, dashed, dotted or markers), its legend entry, its markers.
fn draw_line<'a, DB, XC, YC>(
    chart: &mut Chart<'a, DB, XC, YC>,
    p: &Panel,
    ser: &Series,
    s: f64,
) -> Res<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    XC: Ranged<ValueType = f64>,
    YC: Ranged<ValueType = f64>,
{
    let px = |v: f64| px_at(v, s);
    let lw = ((ser.width as f64 * s).round() as u32).max(1);
    let style = ShapeStyle::from(ser.color).stroke_width(lw);
    let pts: Vec<(f64, f64)> = ser
        .pts
        .iter()
        .copied()
        .filter(|q| q.0.is_finite() && q.1.is_finite())
        .filter(|q| (!p.logx || q.0 > 0.0) && (!p.logy || q.1 > 0.0))
        .collect();
    let ann = match ser.dash {
        Dash::Solid => chart.draw_series(LineSeries::new(pts.clone(), style))?,
        Dash::Dashed => {
            chart.draw_series(DashedLineSeries::new(pts.clone(), px(9.0), px(6.0), style))?
        }
        Dash::Dotted => {
            let c = ser.color;
            let r = (1.3 * s * (ser.width as f64).max(1.0)).max(1.0);
            chart.draw_series(DottedLineSeries::new(pts.clone(), 0, px(6.0), move |xy| {
                Circle::new(xy, r, c.filled())
            }))?
        }
        Dash::Markers => chart.draw_series(
            pts.iter()
                .map(|&xy| Circle::new(xy, px(4.0), ser.color.filled())),
        )?,
    };
    if let Some(name) = &ser.name {
        let (segs, c, k) = (legend_segments(ser.dash), ser.color, px(1.0));
        ann.label(name.as_str()).legend(move |(x, y)| {
            let st = ShapeStyle::from(c).stroke_width(lw);
            let seg = |i: usize| {
                let (a, b, c2, d) = segs[i];
                PathElement::new(vec![(a * k, b * k), (c2 * k, d * k)], st)
            };
            EmptyElement::at((x, y)) + seg(0) + seg(1) + seg(2)
        });
    }
    if ser.markers && ser.dash != Dash::Markers {
        chart.draw_series(
            pts.iter()
                .map(|&xy| Circle::new(xy, px(3.5), ser.color.filled())),
        )?;
    }
    Ok(())
}

/// A series' mark in the legend: three segments (x0, y0, x1, y1) in units of the pixel, so that
/// every dash has one type.
fn legend_segments(dash: Dash) -> [(i32, i32, i32, i32); 3] {
    match dash {
        Dash::Solid => [(0, 0, 12, 0), (12, 0, 24, 0), (24, 0, 24, 0)],
        Dash::Dashed => [(0, 0, 8, 0), (14, 0, 22, 0), (22, 0, 22, 0)],
        Dash::Dotted => [(0, 0, 3, 0), (9, 0, 12, 0), (18, 0, 21, 0)],
        Dash::Markers => [(9, -3, 15, 3), (9, 3, 15, -3), (15, 3, 15, 3)],
    }
}

/// The legend box, where the panel asks for one and a series has a name.
fn draw_legend<'a, DB, XC, YC>(chart: &mut Chart<'a, DB, XC, YC>, p: &Panel, s: f64) -> Res<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    XC: Ranged<ValueType = f64>,
    YC: Ranged<ValueType = f64>,
{
    let pos = match p.legend {
        Legend::None => None,
        Legend::UpperRight => Some(SeriesLabelPosition::UpperRight),
        Legend::UpperLeft => Some(SeriesLabelPosition::UpperLeft),
        Legend::LowerRight => Some(SeriesLabelPosition::LowerRight),
        Legend::LowerLeft => Some(SeriesLabelPosition::LowerLeft),
        Legend::Right => Some(SeriesLabelPosition::UpperRight),
    };
    if let Some(pos) = pos {
        if p.series.iter().any(|s| s.name.is_some()) {
            chart
                .configure_series_labels()
                .position(pos)
                .label_font((FONT, px_at(14.0, s)))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .draw()?;
        }
    }
    Ok(())
}
