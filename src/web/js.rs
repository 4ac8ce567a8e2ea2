//! Small bridges to the browser shared by the pages: what a JavaScript error says, and the text
//! of a file a person chose.

use wasm_bindgen::{JsCast, JsValue};

/// What a JavaScript error says (a `DOMException`'s name and message, an `Error`'s message, a
/// thrown string).
pub fn describe(value: &JsValue) -> String {
    value
        .dyn_ref::<web_sys::DomException>()
        .map(|e| format!("{}: {}", e.name(), e.message()))
        .or_else(|| {
            value
                .dyn_ref::<js_sys::Error>()
                .map(|e| String::from(e.message()))
        })
        .or_else(|| value.as_string())
        .unwrap_or_else(|| "an unknown error".to_string())
}

/// Reads the first file chosen in the `<input type="file">` that fired `ev`, then calls `done`
/// with the file's name and its text, or with why it could not be read. Nothing chosen: nothing
/// happens.
pub fn read_chosen_file(
    ev: &leptos::ev::Event,
    done: impl FnOnce(String, Result<String, String>) + 'static,
) {
    let Some(file) = ev
        .target()
        .and_then(|t| t.dyn_into::<web_sys::HtmlInputElement>().ok())
        .and_then(|input| input.files())
        .and_then(|files| files.get(0))
    else {
        return;
    };
    let name = file.name();
    let promise = file.text();
    leptos::task::spawn_local(async move {
        let text = match wasm_bindgen_futures::JsFuture::from(promise).await {
            Ok(text) => Ok(text.as_string().unwrap_or_default()),
            Err(e) => Err(format!("{name} could not be read: {}", describe(&e))),
        };
        done(name, text);
    });
}
