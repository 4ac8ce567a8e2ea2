//! A heat map on a canvas; clicking a cell reports its data coordinates.

use leptos::prelude::*;
use plotters::prelude::IntoDrawingArea;
use plotters_canvas::CanvasBackend;

use crate::charts::{draw_heat_map, ChartStyle, HeatMap, PlotGeometry};

/// A heat map drawn with plotters; `on_pick` receives the (x, y) of a click or of Enter on the
/// focused canvas (the centre of the map).
#[component]
pub fn HeatMapCanvas(
    /// Accessible name.
    label: &'static str,
    /// What to draw.
    #[prop(into)]
    map: Signal<HeatMap>,
    /// Height in CSS pixels.
    #[prop(default = 320)]
    height_px: u32,
    /// Called with the data coordinates the user picked.
    on_pick: Callback<(f64, f64)>,
) -> impl IntoView {
    let canvas_ref = NodeRef::<leptos::html::Canvas>::new();
    let geometry = StoredValue::new(None::<PlotGeometry>);
    let ratio = StoredValue::new(1.0_f64);
    let (draw_error, set_draw_error) = signal(None::<String>);
    Effect::new(move |_| {
        let map = map.get();
        let Some(canvas) = canvas_ref.get() else {
            return;
        };
        let pixel_ratio = window().device_pixel_ratio().clamp(1.0, 4.0);
        ratio.set_value(pixel_ratio);
        let css_width = f64::from(canvas.client_width().max(120));
        canvas.set_width((css_width * pixel_ratio).round() as u32);
        canvas.set_height((f64::from(height_px) * pixel_ratio).round() as u32);
        let Some(backend) = CanvasBackend::with_canvas_object(canvas) else {
            set_draw_error.set(Some("This browser gave no 2-D canvas to draw on.".into()));
            return;
        };
        let area = backend.into_drawing_area();
        let result = draw_heat_map(&area, &map, ChartStyle { pixel_ratio }).and_then(|g| {
            geometry.set_value(Some(g));
            area.present()
        });
        set_draw_error.set(
            result
                .err()
                .map(|e| format!("The map could not be drawn: {e}")),
        );
    });
    let pick = move |ev: leptos::ev::MouseEvent| {
        let r = ratio.get_value();
        let (px, py) = (ev.offset_x() * r, ev.offset_y() * r);
        let picked = geometry.with_value(|g| {
            g.as_ref()
                .filter(|g| g.contains(px, py))
                .map(|g| (g.x_at(px), g.y_at(py)))
        });
        if let Some(p) = picked {
            on_pick.run(p);
        }
    };
    view! {
        <figure class="chart">
            <canvas
                node_ref=canvas_ref
                role="img"
                aria-label=label
                style=format!("height: {height_px}px; cursor: pointer")
                on:click=pick
            >
                {label}
            </canvas>
            <figcaption class="legend">
                <span class="chart-title">{label}</span>
                <span class="colour-scale" aria-hidden="true"></span>
                {move || map.with(|m| format!("{:.1} … {:.1}", m.value_range.start, m.value_range.end))}
                {move || draw_error.get().map(|e| view! { <span class="chart-error" role="alert">{e}</span> })}
            </figcaption>
        </figure>
    }
}
