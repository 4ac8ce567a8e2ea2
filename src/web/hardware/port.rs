//! Byte ports the Hardware page talks through: a serial port opened with WebSerial, or the
//! virtual device (the emulator running in the page). Both deliver what arrives, and their
//! closing, to a [`Sink`] called from the browser's event loop (never from inside a write), and
//! both take bytes with [`Port::write`].

use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::Duration;

use leptos::prelude::{set_interval_with_handle, window, IntervalHandle};
use wasm_bindgen::closure::Closure;
use wasm_bindgen::{JsCast, JsValue};
use web_sys::{
    FlowControlType, ParityType, ReadableStreamDefaultReader, SerialOptions, SerialPort,
    WritableStreamDefaultWriter,
};

use crate::protocol::device::DeviceEmulator;
use crate::web::js::describe;

/// What a port reports.
pub enum PortEvent {
    /// Bytes arrived.
    Bytes(Vec<u8>),
    /// The port closed under us (unplugged, a read or write error), with why.
    Closed(String),
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

/// How often the virtual device runs.
const VIRTUAL_TICK: Duration = Duration::from_millis(10);
/// Frames the virtual device runs at most per tick, so a tick stays short; behind the clock, it
/// catches up over the next ticks.
const MAX_VIRTUAL_FRAMES_PER_TICK: usize = 400;

struct VirtualState {
    device: DeviceEmulator,
    started_s: f64,
    time_scale: f64,
    inbox: Vec<u8>,
    out: Vec<u8>,
}

/// The device emulator in the page, behind the same protocol bytes as a serial device.
pub struct VirtualLink {
    state: Rc<RefCell<VirtualState>>,
    alive: Rc<Cell<bool>>,
    sink: Sink,
    interval: Option<IntervalHandle>,
}

impl VirtualLink {
    /// Powers `device` on at `time_scale` device seconds per wall second.
    pub fn start(device: DeviceEmulator, time_scale: f64, sink: Sink) -> Result<Self, String> {
        let state = Rc::new(RefCell::new(VirtualState {
            device,
            started_s: now_s(),
            time_scale,
            inbox: Vec::new(),
            out: Vec::with_capacity(64 * 1024),
        }));
        let alive = Rc::new(Cell::new(true));
        let tick = {
            let state = Rc::clone(&state);
            let alive = Rc::clone(&alive);
            let sink = Rc::clone(&sink);
            move || {
                if !alive.get() {
                    return;
                }
                let bytes = {
                    let Ok(mut s) = state.try_borrow_mut() else {
                        return;
                    };
                    let s = &mut *s;
                    let due_s = (now_s() - s.started_s) * s.time_scale;
                    let inbox = std::mem::take(&mut s.inbox);
                    s.device.receive(&inbox, &mut s.out);
                    let mut frames = 0;
                    while s.device.time_s() + s.device.frame_period_s() <= due_s
                        && frames < MAX_VIRTUAL_FRAMES_PER_TICK
                    {
                        s.device.step_frame(&mut s.out);
                        frames += 1;
                    }
                    std::mem::take(&mut s.out)
                };
                if !bytes.is_empty() {
                    sink(PortEvent::Bytes(bytes));
                }
            }
        };
        let interval = set_interval_with_handle(tick, VIRTUAL_TICK)
            .map_err(|e| format!("the virtual device could not start: {}", describe(&e)))?;
        Ok(Self {
            state,
            alive,
            sink,
            interval: Some(interval),
        })
    }

    /// Sends `bytes` to the device (it reads them at its next tick).
    pub fn write(&self, bytes: &[u8]) {
        if let Ok(mut s) = self.state.try_borrow_mut() {
            s.inbox.extend_from_slice(bytes);
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

    /// Switches the device off.
    pub fn close(&mut self) {
        self.alive.set(false);
        if let Some(i) = self.interval.take() {
            i.clear();
        }
    }
}

impl Drop for VirtualLink {
    fn drop(&mut self) {
        self.close();
    }
}

/// A port of either kind.
pub enum Port {
    /// WebSerial.
    Serial(SerialLink),
    /// The emulator in the page.
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
