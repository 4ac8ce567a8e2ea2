//! Byte ports the Hardware page talks through: a serial port opened with WebSerial, or the
//! virtual device (the emulator running in a worker of its own). Both deliver what arrives, and their
//! closing, to a [`Sink`] called from the browser's event loop (never from inside a write), and
//! both take bytes with [`Port::write`].

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::Duration;

use leptos::prelude::window;
use wasm_bindgen::closure::Closure;
use wasm_bindgen::{JsCast, JsValue};
use web_sys::{
    ErrorEvent, FlowControlType, MessageEvent, ParityType, ReadableStreamDefaultReader,
    SerialOptions, SerialPort, Worker, WritableStreamDefaultWriter,
};

use crate::protocol::device_worker::DeviceStart;
use crate::web::components::pool::module_worker;
use crate::web::js::describe;

/// What a port reports.
pub enum PortEvent {
    /// Bytes arrived.
    Bytes(Vec<u8>),
    /// The port closed under us (unplugged, a read or write error), with why.
    Closed(String),
    /// The port never opened: the virtual device's worker refused its settings, with why.
    Refused(String),
}

/// Where a port delivers what happens.
pub type Sink = Rc<dyn Fn(PortEvent)>;

pub use crate::hardware::serial_settings::SerialSettings;

/// Whether this page can use WebSerial, and if not, why.
pub fn web_serial_unavailable() -> Option<&'static str> {
    let w = window();
    if !w.is_secure_context() {
        return Some(
            "this page was not loaded from a secure origin (https, or http on localhost), and \
             browsers offer WebSerial only there",
        );
    }
    let navigator = w.navigator();
    match js_sys::Reflect::get(&navigator, &JsValue::from_str("serial")) {
        Ok(v) if !v.is_undefined() && !v.is_null() => None,
        _ => Some(
            "this browser has no WebSerial (Firefox and Safari do not implement it; Chrome, Edge \
             and Opera on a desktop do)",
        ),
    }
}

/// A serial port opened with WebSerial.
pub struct SerialLink {
    port: SerialPort,
    writer: WritableStreamDefaultWriter,
    reader: ReadableStreamDefaultReader,
    alive: Rc<Cell<bool>>,
    sink: Sink,
    _on_disconnect: Closure<dyn FnMut(web_sys::Event)>,
}

impl SerialLink {
    /// Asks the person to pick a port (this must follow a click), opens it with `settings`, and
    /// starts reading into `sink`.
    pub async fn open(settings: SerialSettings, sink: Sink) -> Result<SerialLink, String> {
        let serial = window().navigator().serial();
        let port: SerialPort = serial
            .request_port()
            .await
            .map_err(|e| format!("no port chosen ({})", describe(&e)))?
            .unchecked_into();
        let options = SerialOptions::new(settings.baud_rate);
        options.set_data_bits(settings.data_bits);
        options.set_stop_bits(settings.stop_bits);
        options.set_parity(match settings.parity {
            "even" => ParityType::Even,
            "odd" => ParityType::Odd,
            _ => ParityType::None,
        });
        options.set_flow_control(match settings.flow_control {
            "hardware" => FlowControlType::Hardware,
            _ => FlowControlType::None,
        });
        options.set_buffer_size(settings.buffer_size);
        port.open(&options)
            .await
            .map_err(|e| format!("the port could not be opened: {}", describe(&e)))?;
        let writer = port
            .writable()
            .get_writer()
            .map_err(|e| format!("the port cannot be written: {}", describe(&e)))?;
        let reader: ReadableStreamDefaultReader = port.readable().get_reader().unchecked_into();
        let alive = Rc::new(Cell::new(true));
        let on_disconnect = {
            let alive = Rc::clone(&alive);
            let sink = Rc::clone(&sink);
            Closure::<dyn FnMut(web_sys::Event)>::new(move |_| {
                if alive.replace(false) {
                    sink(PortEvent::Closed(
                        "the serial port disappeared (the device was unplugged)".to_string(),
                    ));
                }
            })
        };
        let _ = port
            .add_event_listener_with_callback("disconnect", on_disconnect.as_ref().unchecked_ref());
        let link = SerialLink {
            port,
            writer,
            reader,
            alive,
            sink,
            _on_disconnect: on_disconnect,
        };
        link.start_reading();
        Ok(link)
    }

    fn start_reading(&self) {
        let reader = self.reader.clone();
        let alive = Rc::clone(&self.alive);
        let sink = Rc::clone(&self.sink);
        leptos::task::spawn_local(async move {
            loop {
                let result = wasm_bindgen_futures::JsFuture::from(reader.read()).await;
                if !alive.get() {
                    return;
                }
                let why = match result {
                    Ok(chunk) => {
                        let done = js_sys::Reflect::get(&chunk, &"done".into())
                            .ok()
                            .and_then(|d| d.as_bool())
                            .unwrap_or(true);
                        if done {
                            "the port's input ended".to_string()
                        } else {
                            let value = js_sys::Reflect::get(&chunk, &"value".into())
                                .unwrap_or(JsValue::UNDEFINED);
                            match value.dyn_into::<js_sys::Uint8Array>() {
                                Ok(bytes) => {
                                    sink(PortEvent::Bytes(bytes.to_vec()));
                                    continue;
                                }
                                Err(_) => "the port gave something other than bytes".to_string(),
                            }
                        }
                    }
                    Err(e) => format!("reading the port failed ({})", describe(&e)),
                };
                if alive.replace(false) {
                    sink(PortEvent::Closed(why));
                }
                return;
            }
        });
    }

    /// Sends `bytes`; a failed write closes the link.
    pub fn write(&self, bytes: &[u8]) {
        if bytes.is_empty() || !self.alive.get() {
            return;
        }
        let chunk = js_sys::Uint8Array::from(bytes);
        let promise = self.writer.write_with_chunk(&chunk);
        let alive = Rc::clone(&self.alive);
        let sink = Rc::clone(&self.sink);
        leptos::task::spawn_local(async move {
            if let Err(e) = wasm_bindgen_futures::JsFuture::from(promise).await {
                if alive.replace(false) {
                    sink(PortEvent::Closed(format!(
                        "writing to the port failed ({})",
                        describe(&e)
                    )));
                }
            }
        });
    }

    /// Closes the port cleanly, after what was written has gone out.
    pub fn close(&self) {
        let was_alive = self.alive.replace(false);
        let (port, reader, writer) = (self.port.clone(), self.reader.clone(), self.writer.clone());
        leptos::task::spawn_local(async move {
            // The reader's pending read ends when it is cancelled; both locks must be released
            // before the port can close. A port already gone fails these, which is fine.
            let _ = wasm_bindgen_futures::JsFuture::from(reader.cancel()).await;
            reader.release_lock();
            if was_alive {
                let _ = wasm_bindgen_futures::JsFuture::from(writer.close()).await;
            }
            writer.release_lock();
            let _ = wasm_bindgen_futures::JsFuture::from(port.close()).await;
        });
    }
}

/// Wall time, seconds.
pub fn now_s() -> f64 {
    window().performance().map_or(0.0, |p| p.now()) / 1000.0
}

/// The name of the `<html>` attribute that says the virtual device runs in its worker ("on"
/// while such a worker lives), for a person's devtools and the browser tests.
const DEVICE_WORKER_ATTRIBUTE: &str = "data-device-worker";

thread_local! {
    /// Device workers started and not yet terminated.
    static DEVICE_WORKERS: Cell<usize> = const { Cell::new(0) };
}

/// The virtual device: the emulator in a worker of the computation module (the plant lives in
/// that module, not the page's), behind the same protocol bytes as a serial device. The worker
/// ticks it on its own timer (`cutlab::protocol::device_worker`); the bytes the host writes
/// before the worker is ready wait here.
pub struct VirtualLink {
    worker: Worker,
    /// What the host wrote before the worker was ready; `None` once it is.
    waiting: Rc<RefCell<Option<Vec<u8>>>>,
    alive: Rc<Cell<bool>>,
    /// The worker was terminated.
    closed: bool,
    sink: Sink,
    _on_message: Closure<dyn FnMut(MessageEvent)>,
    _on_error: Closure<dyn FnMut(ErrorEvent)>,
}

impl VirtualLink {
    /// Starts a worker and powers on the device `request` describes in it; `Err` says why the
    /// worker did not start. A device the worker cannot start is reported to `sink` as
    /// [`PortEvent::Refused`].
    pub fn start(request: DeviceStart, sink: Sink) -> Result<Self, String> {
        let worker = module_worker().map_err(|e| format!("its worker did not start ({e})"))?;
        let waiting = Rc::new(RefCell::new(Some(Vec::new())));
        let alive = Rc::new(Cell::new(true));
        let on_message = {
            let (worker, waiting, alive, sink) = (
                worker.clone(),
                Rc::clone(&waiting),
                Rc::clone(&alive),
                Rc::clone(&sink),
            );
            let start = request.to_json();
            Closure::<dyn FnMut(MessageEvent)>::new(move |event: MessageEvent| {
                if !alive.get() {
                    return;
                }
                let data = event.data();
                let field = |name: &str| {
                    js_sys::Reflect::get(&data, &name.into()).unwrap_or(JsValue::UNDEFINED)
                };
                match field("kind").as_string().as_deref() {
                    Some("ready") => {
                        let _ =
                            worker.post_message(&message("device_start", &start.as_str().into()));
                        if let Some(bytes) = waiting.borrow_mut().take() {
                            send(&worker, &bytes);
                        }
                    }
                    Some("device_bytes") => {
                        if let Ok(bytes) = field("bytes").dyn_into::<js_sys::Uint8Array>() {
                            sink(PortEvent::Bytes(bytes.to_vec()));
                        }
                    }
                    Some("device_failed") => {
                        alive.set(false);
                        let why = field("message").as_string().unwrap_or_default();
                        sink(PortEvent::Refused(why));
                    }
                    _ => {}
                }
            })
        };
        let on_error = {
            let (alive, sink) = (Rc::clone(&alive), Rc::clone(&sink));
            Closure::<dyn FnMut(ErrorEvent)>::new(move |event: ErrorEvent| {
                // Reported here, in the page, as the link's end.
                event.prevent_default();
                if alive.replace(false) {
                    sink(PortEvent::Closed(format!(
                        "the virtual device's worker stopped: {}",
                        event.message()
                    )));
                }
            })
        };
        worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
        count_device_worker(1);
        Ok(Self {
            worker,
            waiting,
            alive,
            closed: false,
            sink,
            _on_message: on_message,
            _on_error: on_error,
        })
    }

    /// Sends `bytes` to the device (it reads them at its next tick).
    pub fn write(&self, bytes: &[u8]) {
        if bytes.is_empty() || !self.alive.get() {
            return;
        }
        match self.waiting.borrow_mut().as_mut() {
            Some(waiting) => waiting.extend_from_slice(bytes),
            None => send(&self.worker, bytes),
        }
    }

    /// Pulls the virtual cable: the port closes at once, as a USB adapter pulled out does.
    pub fn unplug(&self) {
        if self.alive.replace(false) {
            let sink = Rc::clone(&self.sink);
            // Reported from the event loop, not from inside the caller.
            leptos::prelude::set_timeout(
                move || {
                    sink(PortEvent::Closed(
                        "the virtual device's cable was pulled".to_string(),
                    ))
                },
                Duration::ZERO,
            );
        }
    }

    /// Switches the device off: its worker ends.
    pub fn close(&mut self) {
        self.alive.set(false);
        if std::mem::replace(&mut self.closed, true) {
            return;
        }
        self.worker.set_onmessage(None);
        self.worker.set_onerror(None);
        self.worker.terminate();
        count_device_worker(-1);
    }
}

impl Drop for VirtualLink {
    fn drop(&mut self) {
        self.close();
    }
}

/// `{ name: value }`, a message to the device's worker.
fn message(name: &str, value: &JsValue) -> JsValue {
    let object = js_sys::Object::new();
    let _ = js_sys::Reflect::set(&object, &name.into(), value);
    object.into()
}

/// Posts what the host wrote to the device's worker, the copy's buffer transferred.
fn send(worker: &Worker, bytes: &[u8]) {
    if bytes.is_empty() {
        return;
    }
    let array = js_sys::Uint8Array::from(bytes);
    let transfer = js_sys::Array::of1(&array.buffer());
    // A worker that cannot take a message has failed, which its onerror reports.
    let _ = worker.post_message_with_transfer(&message("device_bytes", &array), &transfer);
}

/// Counts a device worker started (+1) or terminated (−1), and marks on `<html>` whether one
/// runs.
fn count_device_worker(change: isize) {
    let running = DEVICE_WORKERS.with(|n| {
        n.set(n.get().saturating_add_signed(change));
        n.get()
    });
    let Some(html) = window().document().and_then(|d| d.document_element()) else {
        return;
    };
    let _ = if running > 0 {
        html.set_attribute(DEVICE_WORKER_ATTRIBUTE, "on")
    } else {
        html.remove_attribute(DEVICE_WORKER_ATTRIBUTE)
    };
}

/// A port of either kind.
pub enum Port {
    /// WebSerial.
    Serial(SerialLink),
    /// The emulator in its worker.
    Virtual(VirtualLink),
}

impl Port {
    /// Sends `bytes`.
    pub fn write(&self, bytes: &[u8]) {
        match self {
            Port::Serial(s) => s.write(bytes),
            Port::Virtual(v) => v.write(bytes),
        }
    }

    /// Closes it cleanly.
    pub fn close(&mut self) {
        match self {
            Port::Serial(s) => s.close(),
            Port::Virtual(v) => v.close(),
        }
    }

    /// Whether it is the virtual device.
    pub fn is_virtual(&self) -> bool {
        matches!(self, Port::Virtual(_))
    }
}
