//! The library's `log` records on the browser's console, and a panic as a console error that also
//! reaches `window.raypipeStatus.error`, so that a page that stops drawing says why.

use wasm_bindgen::JsValue;

struct Console;

impl log::Log for Console {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Info && metadata.target().starts_with("raypipe")
    }

    fn log(&self, record: &log::Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let line = JsValue::from(format!("{}", record.args()));
        match record.level() {
            log::Level::Error => web_sys::console::error_1(&line),
            log::Level::Warn => web_sys::console::warn_1(&line),
            _ => web_sys::console::info_1(&line),
        }
    }

    fn flush(&self) {}
}

static CONSOLE: Console = Console;

/// Installs the logger and the panic hook, once.
pub fn install() {
    if log::set_logger(&CONSOLE).is_ok() {
        log::set_max_level(log::LevelFilter::Info);
        std::panic::set_hook(Box::new(|info| {
            let line = format!("raypipe stopped: {info}");
            web_sys::console::error_1(&JsValue::from(&line));
            if let Some(window) = web_sys::window()
                && let Ok(status) = js_sys::Reflect::get(&window, &"raypipeStatus".into())
                && status.is_object()
            {
                let _ = js_sys::Reflect::set(&status, &"error".into(), &line.into());
            }
        }));
    }
}
