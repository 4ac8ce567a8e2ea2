//! Which section of the lab is shown, kept in the URL hash (`#/signal`) so a link or the browser's
//! back button lands on the same section.

use leptos::prelude::*;

pub use crate::sections::Page;

/// The part of the hash after the page, e.g. `"controllers"` for `#/learn/controllers`.
pub fn sub_path(hash: &str) -> Option<&str> {
    let path = hash.trim_start_matches('#').trim_start_matches('/');
    let path = path.split('?').next().unwrap_or_default();
    path.split_once('/')
        .map(|(_, rest)| rest)
        .filter(|r| !r.is_empty())
}

/// The `key=value` pairs after `?` in a hash such as `#/simulate?preset=kim-step-doc&kp=0.3`,
/// percent-decoded.
pub fn query_params(hash: &str) -> Vec<(String, String)> {
    let Some((_, query)) = hash.split_once('?') else {
        return Vec::new();
    };
    query
        .split('&')
        .filter_map(|pair| pair.split_once('='))
        .map(|(k, v)| (decode(k), decode(v)))
        .collect()
}

fn decode(text: &str) -> String {
    js_sys::decode_uri_component(text)
        .ok()
        .and_then(|s| s.as_string())
        .unwrap_or_else(|| text.to_string())
}

fn encode(text: &str) -> String {
    js_sys::encode_uri_component(text)
        .as_string()
        .unwrap_or_default()
}

/// The hash of `page` with `params` as its query.
pub fn hash_with_query(page: Page, params: &[(String, String)]) -> String {
    let query: Vec<String> = params
        .iter()
        .map(|(k, v)| format!("{}={}", encode(k), encode(v)))
        .collect();
    if query.is_empty() {
        page.href()
    } else {
        format!("{}?{}", page.href(), query.join("&"))
    }
}

/// Puts `params` in the address bar without a new history entry or a page change, so a link
/// copied from it reproduces what is on screen.
pub fn replace_query(page: Page, params: &[(String, String)]) {
    let hash = hash_with_query(page, params);
    if window().location().hash().ok().as_deref() == Some(hash.as_str()) {
        return;
    }
    if let Ok(history) = window().history() {
        let _ = history.replace_state_with_url(&wasm_bindgen::JsValue::NULL, "", Some(&hash));
    }
}

/// The current page, following the URL hash.
pub fn use_current_page() -> ReadSignal<Page> {
    let read = || {
        window()
            .location()
            .hash()
            .ok()
            .and_then(|h| Page::from_hash(&h))
            .unwrap_or(Page::HOME)
    };
    let (page, set_page) = signal(read());
    let handle = window_event_listener(leptos::ev::hashchange, move |_| set_page.set(read()));
    on_cleanup(move || handle.remove());
    page
}
