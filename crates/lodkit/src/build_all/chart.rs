//! The error-against-triangle-count chart of `report.md`, as SVG.
//!
//! Log–log axes; one line per series. The output depends only on the data
//! (no fonts are measured, text is emitted as SVG `<text>`), so reruns are
//! byte-identical.

use plotters::prelude::*;

/// One named line of `(x, error)` points (x: triangles, bytes, ...).
pub struct Series<'a> {
    pub name: &'a str,
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
}

/// Renders the series into an SVG document, triangles on the x axis.
/// Points with a non-positive or non-finite coordinate are skipped (they
/// cannot sit on a log axis).
pub fn error_chart(title: &str, series: &[Series]) -> anyhow::Result<String> {
    log_chart(title, "triangles", series)
}

/// [`error_chart`] with `x_desc` naming the x axis (e.g. bytes received).
pub fn log_chart(title: &str, x_desc: &str, series: &[Series]) -> anyhow::Result<String> {
    let finite = |(x, y): &(f64, f64)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite();
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied().filter(finite))
        .collect();
    anyhow::ensure!(!all.is_empty(), "nothing to chart");
    let (xmin, xmax) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (ymin, ymax) = all
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 440)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(
                (xmin / 1.3..xmax * 1.3).log_scale(),
                (ymin / 1.5..ymax * 1.5).log_scale(),
            )
            .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
        chart
            .configure_mesh()
            .x_labels(6)
            .y_labels(6)
            .light_line_style(RGBColor(235, 235, 235))
            .x_desc(x_desc)
            .y_desc("error (object units)")
            .y_label_formatter(&|v| format!("{v:.1e}"))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .draw()
            .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
        for s in series {
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(finite).collect();
            let color = s.color;
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(|e| anyhow::anyhow!("chart: {e}"))?
                .label(s.name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow::anyhow!("chart: {e}"))?;
        root.present().map_err(|e| anyhow::anyhow!("chart: {e}"))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_has_the_series_and_is_deterministic() {
        let s = || {
            vec![
                Series {
                    name: "measured max",
                    points: vec![(1e3, 1e-2), (1e4, 1e-3), (1e5, f64::NAN)],
                    color: RED,
                },
                Series {
                    name: "measured mean",
                    points: vec![(1e3, 1e-3), (1e4, 1e-4)],
                    color: BLUE,
                },
            ]
        };
        let a = error_chart("t", &s()).unwrap();
        assert_eq!(a, error_chart("t", &s()).unwrap());
        assert!(a.starts_with("<svg") && a.contains("measured mean") && a.contains("triangles"));
        assert!(error_chart("t", &[]).is_err());
    }
}
