//! A chart on a canvas that a person can explore.
//!
//! Wheel zooms the horizontal axis around the pointer, dragging pans, a double click resets;
//! with the keyboard (the chart is focusable): ← → pan, + − zoom, 0 resets. Hovering shows a
//! cursor line and a readout of every visible series at that x. Legend entries are toggle buttons.
//! Charts given the same `x_view` signal share their horizontal axis (linked time axes).
//!
//! The canvas backing store is sized in device pixels (CSS size × `devicePixelRatio`) and the
//! chart style scales fonts and lines by the same ratio, so charts are crisp on high-DPI screens.
//! Long series are reduced by min/max decimation to about two points per pixel before drawing.

use std::ops::Range;

use leptos::prelude::*;
use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, IntoDrawingArea};
use plotters_canvas::CanvasBackend;
use wasm_bindgen::closure::Closure;
use wasm_bindgen::JsCast;

use crate::charts::view::{nearest, pan, visible, zoom};
use crate::charts::{draw_line_chart, ChartStyle, DrawResult, LineChart, PlotGeometry};
use crate::web::components::download::{download_canvas_png, png_name};
use crate::web::components::runner::Debounce;

/// Formats a readout value with a sensible number of digits.
fn readout(value: f64) -> String {
    let magnitude = value.abs();
    if !value.is_finite() {
        "—".to_string()
    } else if magnitude >= 1000.0 {
        format!("{value:.0}")
    } else if magnitude >= 10.0 {
        format!("{value:.1}")
    } else {
        format!("{value:.3}")
    }
}

/// The canvas's CSS width in pixels, reported by a `ResizeObserver` once the browser has laid the
/// page out and again whenever it changes (`None` until then). Reading `clientWidth` instead
/// forces a layout whenever the page changed since the last one: about 30 ms on a page's first
/// frame, inside the task that mounts it. Without `ResizeObserver`, `clientWidth` once.
pub fn observed_width(canvas_ref: NodeRef<leptos::html::Canvas>) -> ReadSignal<Option<u32>> {
    let (width, set_width) = signal(None::<u32>);
    type Observing = (web_sys::ResizeObserver, Closure<dyn FnMut(js_sys::Array)>);
    let observing = StoredValue::new_local(None::<Observing>);
    Effect::new(move |_| {
        let Some(canvas) = canvas_ref.get() else {
            return;
        };
        let report = Closure::<dyn FnMut(js_sys::Array)>::new(move |entries: js_sys::Array| {
            let Ok(entry) = entries.get(0).dyn_into::<web_sys::ResizeObserverEntry>() else {
                return;
            };
            let px = entry.content_rect().width().round().clamp(0.0, 100_000.0) as u32;
            if width.try_get_untracked() != Some(Some(px)) {
                let _ = set_width.try_set(Some(px));
            }
        });
        match web_sys::ResizeObserver::new(report.as_ref().unchecked_ref()) {
            Ok(observer) => {
                observer.observe(&canvas);
                observing.set_value(Some((observer, report)));
            }
            Err(_) => set_width.set(Some(canvas.client_width().max(0) as u32)),
        }
    });
    on_cleanup(move || {
        observing.try_with_value(|o| {
            if let Some((observer, _)) = o {
                observer.disconnect();
            }
        });
    });
    width
}

/// Narrowest a chart is drawn, CSS pixels.
const MIN_CHART_WIDTH_PX: u32 = 120;

/// Sizes `canvas`'s bitmap for `css_width_px` × `height_px` CSS pixels (at least
/// [`MIN_CHART_WIDTH_PX`] wide) at the screen's pixel ratio, which it returns: a chart drawn at
/// that ratio stays sharp on a high-density screen.
pub fn size_bitmap(canvas: &web_sys::HtmlCanvasElement, css_width_px: u32, height_px: u32) -> f64 {
    let pixel_ratio = window().device_pixel_ratio().clamp(1.0, 4.0);
    let css_width = f64::from(css_width_px.max(MIN_CHART_WIDTH_PX));
    canvas.set_width((css_width * pixel_ratio).round() as u32);
    canvas.set_height((f64::from(height_px) * pixel_ratio).round() as u32);
    pixel_ratio
}

/// What a canvas chart keeps of its last drawing: the pixel ratio and the plot's geometry, to map
/// the pointer to data, and why it could not be drawn, to show instead.
#[derive(Clone, Copy)]
pub struct CanvasDrawing {
    pub ratio: StoredValue<f64>,
    pub geometry: StoredValue<Option<PlotGeometry>>,
    pub error: WriteSignal<Option<String>>,
}

impl CanvasDrawing {
    /// Draws with `draw` on `canvas`, its bitmap sized for `css_width_px` × `height_px` at the
    /// screen's pixel ratio; a failure reads "The `what` could not be drawn: …".
    pub fn draw(
        self,
        canvas: web_sys::HtmlCanvasElement,
        css_width_px: u32,
        height_px: u32,
        what: &str,
        draw: impl FnOnce(&DrawingArea<CanvasBackend, Shift>, ChartStyle) -> DrawResult<CanvasBackend>,
    ) {
        let pixel_ratio = size_bitmap(&canvas, css_width_px, height_px);
        self.ratio.set_value(pixel_ratio);
        let Some(backend) = CanvasBackend::with_canvas_object(canvas) else {
            let _ = self
                .error
                .try_set(Some("This browser gave no 2-D canvas to draw on.".into()));
            return;
        };
        let area = backend.into_drawing_area();
        let result = draw(&area, ChartStyle { pixel_ratio }).and_then(|g| {
            self.geometry.set_value(Some(g));
            area.present()
        });
        let _ = self.error.try_set(
            result
                .err()
                .map(|e| format!("The {what} could not be drawn: {e}")),
        );
    }
}

/// An explorable line chart drawn with plotters on a canvas.
#[component]
pub fn ChartCanvas(
    /// Accessible name of the chart, e.g. "Magnitude response".
    label: &'static str,
    /// What to draw.
    #[prop(into)]
    chart: Signal<LineChart>,
    /// Height in CSS pixels; the width follows the layout.
    #[prop(default = 260)]
    height_px: u32,
    /// The shown horizontal range, shared by linked charts; `None` shows everything.
    #[prop(optional)]
    x_view: Option<RwSignal<Option<Range<f64>>>>,
) -> impl IntoView {
    let x_view = x_view.unwrap_or_else(|| RwSignal::new(None));
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();
    let width = observed_width(canvas_ref);
    let hidden = RwSignal::new(Vec::<bool>::new());
    let geometry = StoredValue::new(None::<PlotGeometry>);
    let ratio = StoredValue::new(1.0_f64);
    let hover_x = RwSignal::new(None::<f64>);
    let drag_from = StoredValue::new(None::<(f64, Range<f64>)>);
    let (draw_error, set_draw_error) = signal(None::<String>);
    let drawing = CanvasDrawing {
        ratio,
        geometry,
        error: set_draw_error,
    };

    // The chart as shown: zoomed, with hidden series removed and long series decimated.
    let shown = Memo::new(move |_| {
        let width_px = width.get().unwrap_or(800).max(MIN_CHART_WIDTH_PX) as usize;
        chart.with(|c| hidden.with(|h| visible(c, x_view.get().as_ref(), h, 2 * width_px)))
    });

    // Each chart draws in a task of its own (a page redraws five at once when a run ends, and
    // together they took longer than a task should); a draw superseded before it ran is skipped.
    let draws = Debounce::to_next_task();
    Effect::new(move |_| {
        let shown = shown.get();
        // Nothing to draw on until the page is laid out and the width reported.
        let Some(css_width) = width.get() else {
            return;
        };
        draws.request(move || {
            let Some(canvas) = canvas_ref.get_untracked() else {
                return;
            };
            drawing.draw(canvas, css_width, height_px, "chart", |area, style| {
                draw_line_chart(area, &shown, style)
            });
        });
    });

    // Pointer position in backend pixels → data x, if inside the plotting area.
    let data_x_at = move |offset_x: f64, offset_y: f64| -> Option<f64> {
        let r = ratio.get_value();
        let (px, py) = (offset_x * r, offset_y * r);
        geometry.with_value(|g| {
            g.as_ref()
                .filter(|g| g.contains(px, py))
                .map(|g| g.x_at(px))
        })
    };
    let current_range = move || shown.with_untracked(|s| s.x.range.clone());
    let x_scale = move || chart.with_untracked(|c| c.x.scale);
    let plot_width_css = move || {
        geometry.with_value(|g| {
            g.as_ref()
                .map_or(1.0, |g| f64::from((g.x_px.end - g.x_px.start).max(1)))
        }) / ratio.get_value()
    };

    let on_wheel = move |ev: leptos::ev::WheelEvent| {
        let Some(anchor) = data_x_at(ev.offset_x(), ev.offset_y()) else {
            return;
        };
        ev.prevent_default();
        let factor = (ev.delta_y() * 0.0015).exp().clamp(0.2, 5.0);
        x_view.set(Some(zoom(&current_range(), anchor, factor, x_scale())));
    };
    let on_pointer_down = move |ev: leptos::ev::PointerEvent| {
        if data_x_at(ev.offset_x(), ev.offset_y()).is_some() {
            drag_from.set_value(Some((ev.client_x(), current_range())));
        }
    };
    let on_pointer_move = move |ev: leptos::ev::PointerEvent| {
        hover_x.set(data_x_at(ev.offset_x(), ev.offset_y()));
        if let Some((start_x, start_range)) = drag_from.get_value() {
            if ev.buttons() & 1 == 1 {
                let fraction = -(ev.client_x() - start_x) / plot_width_css();
                if fraction != 0.0 {
                    x_view.set(Some(pan(&start_range, fraction, x_scale())));
                }
            } else {
                drag_from.set_value(None);
            }
        }
    };
    let on_pointer_up = move |_| drag_from.set_value(None);
    let on_key = move |ev: leptos::ev::KeyboardEvent| {
        let range = current_range();
        let middle = (range.start + range.end) / 2.0;
        let next = match ev.key().as_str() {
            "ArrowLeft" => Some(pan(&range, -0.1, x_scale())),
            "ArrowRight" => Some(pan(&range, 0.1, x_scale())),
            "+" | "=" => Some(zoom(&range, middle, 0.8, x_scale())),
            "-" | "_" => Some(zoom(&range, middle, 1.25, x_scale())),
            "0" | "Home" => {
                x_view.set(None);
                ev.prevent_default();
                return;
            }
            _ => None,
        };
        if let Some(next) = next {
            ev.prevent_default();
            x_view.set(Some(next));
        }
    };

    let readout_view = move || {
        let x = hover_x.get()?;
        let (x_label, rows) = shown.with(|s| {
            (
                s.x.label.clone(),
                s.series
                    .iter()
                    .filter_map(|series| {
                        nearest(series, x).map(|(_, y)| (series.label.clone(), series.color, y))
                    })
                    .collect::<Vec<_>>(),
            )
        });
        let left_px = geometry.with_value(|g| {
            g.as_ref().map(|g| {
                let t = g.x_scale.fraction(&g.x_range, x);
                (f64::from(g.x_px.start) + t * f64::from(g.x_px.end - g.x_px.start))
                    / ratio.get_value()
            })
        })?;
        Some(view! {
            <div class="chart-cursor" style=format!("left: {left_px:.1}px") aria-hidden="true"></div>
            <div class="chart-readout" aria-hidden="true">
                <div class="readout-x">{format!("{x_label}: {}", readout(x))}</div>
                {rows
                    .into_iter()
                    .map(|(name, color, y)| {
                        view! {
                            <div>
                                <span class="swatch" style=format!("background: {}", color.css())></span>
                                {format!(" {name}: {}", readout(y))}
                            </div>
                        }
                    })
                    .collect_view()}
            </div>
        })
    };

    view! {
        <figure class="chart">
            <div class="chart-stage">
                <canvas
                    node_ref=canvas_ref
                    role="img"
                    aria-label=label
                    tabindex="0"
                    aria-describedby="chart-help"
                    style=format!("height: {height_px}px")
                    on:wheel=on_wheel
                    on:pointerdown=on_pointer_down
                    on:pointermove=on_pointer_move
                    on:pointerup=on_pointer_up
                    on:pointerleave=move |_| hover_x.set(None)
                    on:dblclick=move |_| x_view.set(None)
                    on:keydown=on_key
                >
                    {label}
                </canvas>
                {readout_view}
            </div>
            <ChartLegend
                label=label
                chart=chart
                hidden=hidden
                x_view=x_view
                canvas_ref=canvas_ref
                draw_error=draw_error
                set_draw_error=set_draw_error
            />
        </figure>
    }
}

/// A chart's caption: its title, a toggle button per series, PNG export, Reset zoom while
/// zoomed, and why it could not be drawn.
#[component]
fn ChartLegend(
    label: &'static str,
    chart: Signal<LineChart>,
    /// Which series are hidden, by index.
    hidden: RwSignal<Vec<bool>>,
    x_view: RwSignal<Option<Range<f64>>>,
    canvas_ref: NodeRef<leptos::html::Canvas>,
    draw_error: ReadSignal<Option<String>>,
    set_draw_error: WriteSignal<Option<String>>,
) -> impl IntoView {
    view! {
    <figcaption class="legend">
        <span class="chart-title">{label}</span>
        {move || {
            chart
                .with(|c| {
                    c.series
                        .iter()
                        .enumerate()
                        .map(|(i, s)| {
                            let swatch = format!("background: {}", s.color.css());
                            let is_hidden = move || hidden.with(|h| h.get(i).copied().unwrap_or(false));
                            view! {
                                <button
                                    type="button"
                                    class="legend-item"
                                    aria-pressed=move || if is_hidden() { "false" } else { "true" }
                                    title="Show or hide this series"
                                    on:click=move |_| {
                                        hidden.update(|h| {
                                            if h.len() <= i {
                                                h.resize(i + 1, false);
                                            }
                                            h[i] = !h[i];
                                        })
                                    }
                                >
                                    <span class="swatch" style=swatch></span>
                                    {s.label.clone()}
                                </button>
                            }
                        })
                        .collect_view()
                })
        }}
        <button
            type="button"
            class="chart-reset"
            aria-label=format!("Save {label} as PNG")
            on:click=move |_| {
                if let Some(canvas) = canvas_ref.get_untracked() {
                    let result = download_canvas_png(&canvas, &png_name(label));
                    set_draw_error.set(result.err());
                }
            }
        >
            "PNG"
        </button>
        {move || {
            x_view
                .get()
                .is_some()
                .then(|| {
                    view! {
                        <button type="button" class="chart-reset" on:click=move |_| x_view.set(None)>
                            "Reset zoom"
                        </button>
                    }
                })
        }}
        {move || draw_error.get().map(|e| view! { <span class="chart-error" role="alert">{e}</span> })}
    </figcaption>
    }
}

/// The one help text every chart's canvas points to with `aria-describedby`.
#[component]
pub fn ChartHelp() -> impl IntoView {
    view! {
        <p id="chart-help" class="visually-hidden">
            "Chart controls: mouse wheel or + and − zoom the time axis, drag or the arrow keys pan, "
            "double-click or 0 resets. Legend buttons show or hide a series."
        </p>
    }
}
