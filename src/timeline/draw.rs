//! A trace as a Gantt chart, for readers without Perfetto at hand: one row per track
//! (GPU streams first), nested slices stacked below their parents, one row per counter
//! series, and a time axis in milliseconds. Drawn as SVG with `plotters`; PNG is the
//! same SVG rasterised by `resvg` (labels need a system sans-serif font; without one
//! the bars are drawn unlabelled).

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::HSLColor;

use super::model::{Counter, Slice, Trace, GPU_PID};
use super::TimelineError;

/// Chart size and time window.
#[derive(Clone, Debug)]
pub struct DrawOptions {
    /// Width in pixels, [`WIDTH_RANGE`] (the height follows from the tracks).
    pub width: u32,
    /// The window to draw, in milliseconds from the trace's time origin; the whole
    /// trace where `None`.
    pub from_ms: Option<f64>,
    pub to_ms: Option<f64>,
}

impl Default for DrawOptions {
    fn default() -> Self {
        Self {
            width: 1600,
            from_ms: None,
            to_ms: None,
        }
    }
}

const LABEL_WIDTH: u32 = 300;
/// The chart widths drawn: the labels and a plot of 200 pixels at the least; at most as
/// wide as a PNG of every track stays a reasonable size.
pub const WIDTH_RANGE: std::ops::RangeInclusive<u32> = (LABEL_WIDTH + 220)..=32768;
const ROW_PX: u32 = 16;
const COUNTER_ROWS: u32 = 3;
const TOP_PX: u32 = 36;
const AXIS_PX: u32 = 40;
const FONT_PX: u32 = 11;
/// Roughly how wide one character of an 11 px sans-serif label is.
const CHAR_PX: f64 = 6.2;

/// A bar to draw: time span in ms, row (units from the top), colour and label.
struct Bar {
    x0: f64,
    x1: f64,
    row: u32,
    color: RGBColor,
    label: String,
}

fn draw_error(e: impl std::fmt::Display) -> TimelineError {
    TimelineError::Draw(e.to_string())
}

/// A stable colour per slice name; host waits grey, so that idle time stands out.
fn color_of(name: &str) -> RGBColor {
    if name.starts_with("wait ") {
        return RGBColor(200, 200, 200);
    }
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    });
    let hue = (hash % 360) as f64 / 360.0;
    let lightness = 0.55 + 0.1 * ((hash >> 16) % 3) as f64 / 2.0;
    let (r, g, b) = HSLColor(hue, 0.55, lightness).rgb();
    RGBColor(r, g, b)
}

/// Each slice's depth in its track (slices are sorted, enclosing ones first).
fn depths(slices: &[Slice]) -> Vec<u32> {
    let mut open: Vec<i64> = Vec::new();
    slices
        .iter()
        .map(|s| {
            while open.last().is_some_and(|&end| end <= s.start_ns) {
                open.pop();
            }
            let depth = open.len() as u32;
            open.push(s.end_ns());
            depth
        })
        .collect()
}

/// Lays out the bars of one track from row `top`; returns the rows it takes. Runs of
/// slices narrower than a pixel merge into one unlabelled bar, which keeps the file
/// small however many dispatches a trace holds.
fn track_bars(
    slices: &[Slice],
    top: u32,
    window: (f64, f64),
    ms_per_px: f64,
    bars: &mut Vec<Bar>,
) -> u32 {
    let depth = depths(slices);
    let rows = depth.iter().max().map_or(1, |d| d + 1);
    let mut pending: Vec<Option<Bar>> = (0..rows).map(|_| None).collect();
    for (s, &d) in slices.iter().zip(&depth) {
        let x0 = (s.start_ns as f64 * 1e-6).max(window.0);
        let x1 = (s.end_ns() as f64 * 1e-6).min(window.1);
        if x1 < x0 {
            continue;
        }
        let narrow = (x1 - x0) < ms_per_px;
        let slot = &mut pending[d as usize];
        if let Some(bar) = slot
            .as_mut()
            .filter(|b| narrow && b.label.is_empty() && x0 - b.x1 < ms_per_px)
        {
            bar.x1 = bar.x1.max(x1);
            continue;
        }
        bars.extend(slot.take());
        *slot = Some(Bar {
            x0,
            x1: x1.max(x0 + ms_per_px),
            row: top + d,
            color: color_of(&s.name),
            label: if narrow {
                String::new()
            } else {
                s.name.clone()
            },
        });
    }
    bars.extend(pending.into_iter().flatten());
    rows
}

/// The plot: milliseconds across; y from 0 at the bottom to the number of rows at the top
/// (a row's place is [`row_y`]).
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The window to draw, in ms: the options' bounds, else the trace's extent.
fn time_window(trace: &Trace, options: &DrawOptions) -> Result<(f64, f64), TimelineError> {
    let (t0, t1) = trace
        .extent_ns()
        .ok_or_else(|| TimelineError::Draw("the trace has no slices and no counters".into()))?;
    let window = (
        options.from_ms.unwrap_or(t0 as f64 * 1e-6),
        options.to_ms.unwrap_or(t1 as f64 * 1e-6),
    );
    for (option, bound) in [("--from", window.0), ("--to", window.1)] {
        if !bound.is_finite() {
            return Err(TimelineError::Draw(format!(
                "{option} {bound}: a time window needs finite bounds"
            )));
        }
    }
    if window.1.partial_cmp(&window.0) != Some(std::cmp::Ordering::Greater) {
        return Err(TimelineError::Draw(format!(
            "empty time window {:.3}..{:.3} ms",
            window.0, window.1
        )));
    }
    Ok(window)
}

/// The largest value of a counter series (0 without samples).
fn counter_max(c: &Counter) -> f64 {
    c.samples.iter().map(|&(_, v)| v).fold(0.0, f64::max)
}

/// Where everything goes: the bars, each track's and counter series' label by its first
/// row, the first counter row and the number of rows (at least one).
struct Layout {
    bars: Vec<Bar>,
    labels: Vec<(u32, String)>,
    first_counter_row: u32,
    rows: u32,
}

fn layout(trace: &Trace, window: (f64, f64), ms_per_px: f64) -> Layout {
    // Rows: GPU tracks first, then host tracks, then counters.
    let mut order: Vec<_> = trace.tracks.iter().collect();
    order.sort_by_key(|t| t.pid != GPU_PID);
    let mut bars = Vec::new();
    let mut labels: Vec<(u32, String)> = Vec::new();
    let mut row = 0;
    for t in order {
        labels.push((row, t.name.clone()));
        row += track_bars(&t.slices, row, window, ms_per_px, &mut bars);
    }
    let first_counter_row = row;
    for c in &trace.counters {
        let max = counter_max(c);
        labels.push((row, format!("{} {} (max {max})", c.name, c.series)));
        row += COUNTER_ROWS;
    }
    Layout {
        bars,
        labels,
        first_counter_row,
        rows: row.max(1),
    }
}

/// Row `r` of `rows` spans y from `rows − r` (top) to `rows − r − 1`.
fn row_y(rows: u32, r: f64) -> f64 {
    rows as f64 - r
}

/// The title (device and clock alignment) and, below it, the command that was traced.
fn draw_title(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    trace: &Trace,
) -> Result<(), TimelineError> {
    let title = format!(
        "{} — {}",
        trace
            .metadata
            .get("device")
            .and_then(|d| d.as_str())
            .unwrap_or("splitray timeline"),
        trace
            .metadata
            .get("clock")
            .and_then(|c| c.get("alignment"))
            .and_then(|a| a.as_str())
            .map_or(String::new(), |a| format!("GPU clock aligned: {a}"))
    );
    root.draw(&Text::new(title, (10, 6), ("sans-serif", 13).into_font()))
        .map_err(draw_error)?;
    if let Some(command) = trace.metadata.get("command").and_then(|c| c.as_str()) {
        root.draw(&Text::new(
            command.to_string(),
            (10, 22),
            ("sans-serif", FONT_PX)
                .into_font()
                .color(&RGBColor(90, 90, 90)),
        ))
        .map_err(draw_error)?;
    }
    Ok(())
}

fn draw_row_labels(
    left: &DrawingArea<SVGBackend<'_>, Shift>,
    labels: &[(u32, String)],
) -> Result<(), TimelineError> {
    for (r, name) in labels {
        let y = (TOP_PX + r * ROW_PX + 2) as i32;
        left.draw(&Text::new(
            name.clone(),
            (8, y),
            ("sans-serif", FONT_PX).into_font(),
        ))
        .map_err(draw_error)?;
    }
    Ok(())
}

/// The plot of `rows` rows over `window`, with its time axis.
fn chart<'a, 'b>(
    right: &'a DrawingArea<SVGBackend<'b>, Shift>,
    window: (f64, f64),
    rows: u32,
) -> Result<Chart<'a, 'b>, TimelineError> {
    let mut chart = ChartBuilder::on(right)
        .margin_top(TOP_PX)
        .margin_right(20)
        .x_label_area_size(AXIS_PX)
        .build_cartesian_2d(window.0..window.1, 0.0..rows as f64)
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .disable_y_axis()
        .x_desc("ms")
        .x_labels(12)
        .x_max_light_lines(2)
        .draw()
        .map_err(draw_error)?;
    Ok(chart)
}

/// The bars, then the labels of those wide enough to hold them.
fn draw_bars(
    chart: &mut Chart<'_, '_>,
    bars: &[Bar],
    rows: u32,
    ms_per_px: f64,
) -> Result<(), TimelineError> {
    chart
        .draw_series(bars.iter().map(|b| {
            // A pixel of gap at the end of wide bars tells neighbours apart.
            let x1 = if (b.x1 - b.x0) > 3.0 * ms_per_px {
                b.x1 - ms_per_px
            } else {
                b.x1
            };
            Rectangle::new(
                [
                    (b.x0, row_y(rows, b.row as f64 + 0.08)),
                    (x1, row_y(rows, b.row as f64 + 0.92)),
                ],
                b.color.filled(),
            )
        }))
        .map_err(draw_error)?;
    let font = ("sans-serif", FONT_PX).into_font();
    chart
        .draw_series(
            bars.iter()
                .filter(|b| (b.x1 - b.x0) / ms_per_px > b.label.len() as f64 * CHAR_PX + 4.0)
                .map(|b| {
                    Text::new(
                        b.label.clone(),
                        (b.x0 + 2.0 * ms_per_px, row_y(rows, b.row as f64 + 0.15)),
                        font.clone(),
                    )
                }),
        )
        .map_err(draw_error)?;
    Ok(())
}

/// Each counter series as a step line over its rows, from `first_row` on, scaled to its
/// maximum.
fn draw_counters(
    chart: &mut Chart<'_, '_>,
    counters: &[Counter],
    first_row: u32,
    rows: u32,
    window: (f64, f64),
) -> Result<(), TimelineError> {
    for (i, c) in counters.iter().enumerate() {
        let max = counter_max(c).max(1e-30);
        let base = (first_row + i as u32 * COUNTER_ROWS) as f64;
        let level = |v: f64| {
            row_y(
                rows,
                base + COUNTER_ROWS as f64 - 0.2 - (COUNTER_ROWS as f64 - 0.6) * v / max,
            )
        };
        let mut points = Vec::new();
        for (k, &(t, v)) in c.samples.iter().enumerate() {
            let x = (t as f64 * 1e-6).clamp(window.0, window.1);
            let next = c.samples.get(k + 1).map_or(window.1, |&(t, _)| {
                (t as f64 * 1e-6).clamp(window.0, window.1)
            });
            points.push((x, level(v)));
            points.push((next, level(v)));
        }
        chart
            .draw_series(std::iter::once(PathElement::new(
                points,
                BLUE.stroke_width(1),
            )))
            .map_err(draw_error)?;
    }
    Ok(())
}

/// The chart as an SVG document.
pub fn svg(trace: &Trace, options: &DrawOptions) -> Result<String, TimelineError> {
    if !WIDTH_RANGE.contains(&options.width) {
        return Err(TimelineError::Draw(format!(
            "a width of {} pixels is outside {}..={}",
            options.width,
            WIDTH_RANGE.start(),
            WIDTH_RANGE.end()
        )));
    }
    let window = time_window(trace, options)?;
    let plot_px = options.width - LABEL_WIDTH - 20;
    let ms_per_px = (window.1 - window.0) / plot_px as f64;
    let layout = layout(trace, window, ms_per_px);
    let height = TOP_PX + layout.rows * ROW_PX + AXIS_PX;

    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (options.width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_error)?;
        draw_title(&root, trace)?;
        let (left, right) = root.split_horizontally(LABEL_WIDTH);
        draw_row_labels(&left, &layout.labels)?;
        let mut chart = chart(&right, window, layout.rows)?;
        draw_bars(&mut chart, &layout.bars, layout.rows, ms_per_px)?;
        draw_counters(
            &mut chart,
            &trace.counters,
            layout.first_counter_row,
            layout.rows,
            window,
        )?;
        root.present().map_err(draw_error)?;
    }
    Ok(out)
}

/// The chart as a PNG image (the SVG rasterised).
pub fn png(trace: &Trace, options: &DrawOptions) -> Result<Vec<u8>, TimelineError> {
    let svg = svg(trace, options)?;
    let mut opt = resvg::usvg::Options::default();
    let fonts = opt.fontdb_mut();
    fonts.load_system_fonts();
    let family = fonts
        .faces()
        .flat_map(|f| f.families.iter().map(|(name, _)| name.clone()))
        .min_by_key(|name| match name.as_str() {
            "DejaVu Sans" => 0,
            "Liberation Sans" => 1,
            "Noto Sans" => 2,
            n if n.contains("Sans") => 3,
            _ => 4,
        });
    if let Some(family) = family {
        fonts.set_sans_serif_family(family);
    }
    let tree = resvg::usvg::Tree::from_str(&svg, &opt).map_err(draw_error)?;
    let size = tree.size().to_int_size();
    let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| TimelineError::Draw("image size out of range".into()))?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::default(),
        &mut pixmap.as_mut(),
    );
    pixmap.encode_png().map_err(draw_error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timeline::{Counter, Track, HOST_PID};
    use serde_json::Map;

    fn slice(name: &str, start: i64, end: i64) -> Slice {
        Slice {
            name: name.into(),
            category: "gpu".into(),
            start_ns: start,
            dur_ns: end - start,
            args: Map::new(),
        }
    }

    fn trace() -> Trace {
        Trace {
            tracks: vec![
                Track {
                    pid: HOST_PID,
                    tid: 1,
                    name: "main".into(),
                    slices: vec![slice("wait main@1", 0, 900_000)],
                },
                Track {
                    pid: GPU_PID,
                    tid: 1,
                    name: "main (queue family 0, index 0)".into(),
                    slices: vec![
                        slice("pdacrt-level", 100_000, 800_000),
                        slice("split", 100_000, 300_000),
                    ],
                },
            ],
            counters: vec![Counter {
                pid: GPU_PID,
                name: "pt".into(),
                series: "live paths".into(),
                samples: vec![(0, 10.0), (500_000, 3.0)],
            }],
            ..Default::default()
        }
    }

    #[test]
    fn nested_slices_stack_and_the_svg_names_every_track() {
        let t = trace();
        assert_eq!(depths(&t.tracks[1].slices), [0, 1]);
        let svg = svg(&t, &DrawOptions::default()).unwrap();
        assert!(svg.starts_with("<svg"));
        for text in [
            "main (queue family 0, index 0)",
            "pdacrt-level",
            "pt live paths (max 10)",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        // GPU tracks come first.
        let label = |s: &str| {
            svg.find(&format!(">\n{s}\n</text>"))
                .unwrap_or_else(|| panic!("{s}: {svg}"))
        };
        assert!(label("main (queue family 0, index 0)") < label("main"));
    }

    #[test]
    fn narrow_slices_merge_into_one_bar() {
        let slices: Vec<Slice> = (0..1000).map(|i| slice("k", i * 10, i * 10 + 5)).collect();
        let mut bars = Vec::new();
        track_bars(&slices, 0, (0.0, 10.0), 0.01, &mut bars);
        assert_eq!(bars.len(), 1);
        assert!(bars[0].x1 >= 0.00999 - 1e-9);
    }

    #[test]
    fn png_is_an_image_of_the_chart_size() {
        let options = DrawOptions {
            width: 900,
            ..Default::default()
        };
        let bytes = png(&trace(), &options).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().unwrap();
        assert_eq!(reader.info().width, 900);
        let empty = Trace::default();
        assert!(svg(&empty, &options).is_err());
        let window = DrawOptions {
            from_ms: Some(2.0),
            to_ms: Some(1.0),
            ..options
        };
        assert!(svg(&trace(), &window)
            .unwrap_err()
            .to_string()
            .contains("window"));
    }

    #[test]
    fn widths_outside_the_range_are_refused_and_its_ends_drawn() {
        let at = |width| {
            let options = DrawOptions {
                width,
                ..Default::default()
            };
            svg(&trace(), &options)
        };
        for width in [0, 1, WIDTH_RANGE.start() - 1, WIDTH_RANGE.end() + 1] {
            let err = at(width).unwrap_err().to_string();
            assert!(err.contains(&format!("width of {width} pixels")), "{err}");
        }
        for width in [*WIDTH_RANGE.start(), *WIDTH_RANGE.end()] {
            let svg = at(width).unwrap();
            assert!(svg.contains(&format!("width=\"{width}\"")), "{width}");
        }
    }
}
