//! A heat map on a canvas; clicking a cell, or moving a keyboard cursor over the grid and
//! pressing Enter, reports its data coordinates.

use leptos::prelude::*;

use crate::charts::{draw_heat_map, HeatMap, PlotGeometry};
use crate::web::components::chart::{observed_width, CanvasDrawing};
use crate::web::components::runner::Debounce;

/// A heat map drawn with plotters; `on_pick` receives the (x, y) of a click, or of the keyboard
/// cursor when Enter or Space is pressed on the focused map (the arrow keys move the cursor one
/// cell, Home returns it to the centre; its position is read out beside the map).
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
    let drawing = CanvasDrawing {
        ratio,
        geometry,
        error: set_draw_error,
    };
    // The keyboard cursor as a fraction of each axis's range, at the centre of a cell.
    let cursor = RwSignal::new((0.5_f64, 0.5_f64));
    let cursor_point = move || {
        map.with(|m| {
            let at = |axis: &crate::charts::Axis, t: f64| {
                axis.range.start + t * (axis.range.end - axis.range.start)
            };
            (at(&m.x, cursor.get().0), at(&m.y, cursor.get().1))
        })
    };
    let on_key = move |ev: leptos::ev::KeyboardEvent| {
        let (nx, ny) = map.with(|m| (m.nx.max(1) as f64, m.ny.max(1) as f64));
        let step = |t: f64, cells: f64, by: f64| {
            // Snap to cell centres so repeated presses land on every cell exactly once.
            let cell = ((t * cells - 0.5).round() + by).clamp(0.0, cells - 1.0);
            (cell + 0.5) / cells
        };
        let (fx, fy) = cursor.get_untracked();
        let moved = match ev.key().as_str() {
            "ArrowLeft" => Some((step(fx, nx, -1.0), fy)),
            "ArrowRight" => Some((step(fx, nx, 1.0), fy)),
            "ArrowDown" => Some((fx, step(fy, ny, -1.0))),
            "ArrowUp" => Some((fx, step(fy, ny, 1.0))),
            "Home" => Some((0.5, 0.5)),
            "Enter" | " " => {
                on_pick.run(cursor_point());
                ev.prevent_default();
                return;
            }
            _ => None,
        };
        if let Some(p) = moved {
            cursor.set(p);
            ev.prevent_default();
        }
    };
    let width = observed_width(canvas_ref);
    // Drawn in a task of its own, as the line charts are: the width arrives with the page's
    // first layout, in the same rendering step as the other charts' widths.
    let draws = Debounce::to_next_task();
    Effect::new(move |_| {
        let map = map.get();
        // Nothing to draw on until the page is laid out and the width reported.
        let (Some(canvas), Some(css_width)) = (canvas_ref.get(), width.get()) else {
            return;
        };
        draws.request(move || {
            drawing.draw(canvas, css_width, height_px, "map", |area, style| {
                draw_heat_map(area, &map, style)
            });
        });
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
                aria-label=format!("{label}: arrow keys move a cursor over the map, Enter picks it")
                tabindex="0"
                style=format!("height: {height_px}px; cursor: pointer")
                on:click=pick
                on:keydown=on_key
            >
                {label}
            </canvas>
            <figcaption class="legend">
                <span class="chart-title">{label}</span>
                <span class="colour-scale" aria-hidden="true"></span>
                {move || map.with(|m| format!("{:.1} … {:.1}", m.value_range.start, m.value_range.end))}
                <span class="cursor-readout" aria-live="polite">
                    {move || {
                        let (x, y) = cursor_point();
                        map.with(|m| format!("Cursor: {} = {x:.2}, {} = {y:.2}", m.x.label, m.y.label))
                    }}
                </span>
                {move || draw_error.get().map(|e| view! { <span class="chart-error" role="alert">{e}</span> })}
            </figcaption>
        </figure>
    }
}
