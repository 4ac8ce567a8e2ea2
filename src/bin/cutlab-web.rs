//! The browser app's entry point, built by Trunk. All UI lives in `cutlab::web`.

fn main() {
    cutlab::web::start();
}
