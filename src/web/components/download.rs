//! Saving text the lab produced (CSV traces, JSON metrics and configurations) as a file.

use wasm_bindgen::JsCast;

use crate::closed_loop::config::RunConfiguration;
use crate::closed_loop::definition::RunSpec;
use crate::web::js::describe;

/// Offers `text` as a download named `file_name`. Returns a message if the browser refused.
pub fn download_text(file_name: &str, mime: &str, text: &str) -> Result<(), String> {
    let parts = js_sys::Array::of1(&wasm_bindgen::JsValue::from_str(text));
    download_parts(file_name, mime, &parts)
}

/// Offers the strings of `parts`, joined, as a download named `file_name` (a long recording's
/// CSV in the chunks it was stored in, without joining them in memory first).
pub fn download_parts(file_name: &str, mime: &str, parts: &js_sys::Array) -> Result<(), String> {
    let fail = |what: &str| format!("could not save {file_name}: {what}");
    let options = web_sys::BlobPropertyBag::new();
    options.set_type(mime);
    let blob = web_sys::Blob::new_with_str_sequence_and_options(parts, &options)
        .map_err(|e| fail(&describe(&e)))?;
    let url =
        web_sys::Url::create_object_url_with_blob(&blob).map_err(|_| fail("no object URL"))?;
    let saved = save_url(&url, file_name);
    let _ = web_sys::Url::revoke_object_url(&url);
    saved
}

/// Clicks a link to `url` that downloads it as `file_name`.
fn save_url(url: &str, file_name: &str) -> Result<(), String> {
    let fail = |what: &str| format!("could not save {file_name}: {what}");
    let anchor: web_sys::HtmlAnchorElement = leptos::prelude::document()
        .create_element("a")
        .map_err(|_| fail("no anchor"))?
        .dyn_into()
        .map_err(|_| fail("not an anchor"))?;
    anchor.set_href(url);
    anchor.set_download(file_name);
    anchor.click();
    Ok(())
}

/// Offers what `write` writes (a CSV writer of the core) as a download named `file_name`.
pub fn download_written(
    file_name: &str,
    mime: &str,
    write: impl FnOnce(&mut Vec<u8>) -> std::io::Result<()>,
) -> Result<(), String> {
    let mut bytes = Vec::new();
    write(&mut bytes).map_err(|e| format!("could not save {file_name}: {e}"))?;
    download_text(file_name, mime, &String::from_utf8_lossy(&bytes))
}

/// Offers `runs` as `cutlab-config.json`, with the page's link: the file `cutlab sim --config`
/// and `cutlab compare --config` run again in a terminal.
pub fn download_configuration(runs: Vec<RunSpec>) -> Result<(), String> {
    let link = leptos::prelude::window().location().href().ok();
    let text = RunConfiguration::new(runs, link).to_json();
    download_text("cutlab-config.json", "application/json", &text)
}

/// Offers a canvas's pixels as a PNG download named `file_name`.
pub fn download_canvas_png(
    canvas: &web_sys::HtmlCanvasElement,
    file_name: &str,
) -> Result<(), String> {
    let url = canvas
        .to_data_url_with_type("image/png")
        .map_err(|_| format!("could not save {file_name}: the canvas gave no image"))?;
    save_url(&url, file_name)
}

/// A file name from a chart's label: "Cutting force" → "cutting-force.png".
pub fn png_name(label: &str) -> String {
    let slug = crate::input::file_slug(label);
    format!("{slug}.png")
}
