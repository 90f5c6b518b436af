//! `--preview`: a window that shows the tone-mapped image after every pass.
//! Built only with `--features preview` (minifb, X11 loaded at run time), so
//! the default build needs no windowing libraries.
//!
//! The window lives on a thread of its own, which keeps it responsive
//! while passes run; the render hands it frames through a channel of one,
//! dropping a frame when the window has not shown the last one yet.
//! Closing the window stops the render as Ctrl-C does.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use tracer::film::tonemap::Tonemap;
use tracer::film::Image;
use tracer::settings::Crop;
use tracer::{Error, Result};

/// Whether this build has the preview window.
pub const AVAILABLE: bool = cfg!(feature = "preview");

/// An image as the window shows it: 0RGB words, row-major.
#[cfg_attr(not(feature = "preview"), allow(dead_code))]
pub fn frame(image: &Image, tonemap: Tonemap, exposure: f32) -> Vec<u32> {
    image
        .pixels
        .iter()
        .map(|&c| {
            let [r, g, b] = tracer::film::tonemap::to_8bit(c, tonemap, exposure);
            (r as u32) << 16 | (g as u32) << 8 | b as u32
        })
        .collect()
}

#[cfg(feature = "preview")]
pub struct Preview {
    frames: Option<std::sync::mpsc::SyncSender<Vec<u32>>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

#[cfg(feature = "preview")]
impl Preview {
    /// Opens a window the size of `crop` (the pixels rendered) named
    /// after the scene; `interrupt` is set when the user closes it, and
    /// closes it when set.
    pub fn open(name: &str, crop: Crop, interrupt: Arc<AtomicBool>) -> Result<Preview> {
        use std::sync::atomic::Ordering;
        let (w, h) = (crop.width() as usize, crop.height() as usize);
        let title = format!("tracer: {name}");
        let (frames, incoming) = std::sync::mpsc::sync_channel::<Vec<u32>>(1);
        let (opened, opened_rx) = std::sync::mpsc::channel::<std::result::Result<(), String>>();
        let thread = std::thread::spawn(move || {
            let options = minifb::WindowOptions {
                resize: true,
                scale_mode: minifb::ScaleMode::AspectRatioStretch,
                ..minifb::WindowOptions::default()
            };
            let mut window = match minifb::Window::new(&title, w, h, options) {
                Ok(window) => {
                    let _ = opened.send(Ok(()));
                    window
                }
                Err(e) => {
                    let _ = opened.send(Err(e.to_string()));
                    return;
                }
            };
            window.set_target_fps(30);
            let mut shown = vec![0u32; w * h];
            while window.is_open() && !interrupt.load(Ordering::Relaxed) {
                // The newest frame wins; a closed channel just means the render is over.
                while let Ok(frame) = incoming.try_recv() {
                    shown = frame;
                }
                if window.update_with_buffer(&shown, w, h).is_err() {
                    break;
                }
            }
            if !window.is_open() {
                interrupt.store(true, Ordering::SeqCst);
            }
        });
        match opened_rx.recv() {
            Ok(Ok(())) => Ok(Preview {
                frames: Some(frames),
                thread: Some(thread),
            }),
            Ok(Err(e)) => Err(Error::Preview(format!(
                "cannot open the preview window: {e} (is DISPLAY set?)"
            ))),
            Err(_) => Err(Error::Preview("the preview window failed to start".into())),
        }
    }

    pub fn show(&mut self, image: &Image, tonemap: Tonemap, exposure: f32) {
        if let Some(frames) = &self.frames {
            let _ = frames.try_send(frame(image, tonemap, exposure));
        }
    }

    /// Keeps showing the last image until the window is closed or Ctrl-C.
    pub fn wait(mut self) {
        self.frames = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Without the feature there is no window: this type has no values, and
/// the command line refuses `--preview` before it would need one.
#[cfg(not(feature = "preview"))]
pub enum Preview {}

#[cfg(not(feature = "preview"))]
impl Preview {
    pub fn open(_: &str, _: Crop, _: Arc<AtomicBool>) -> Result<Preview> {
        Err(Error::Preview(
            "this build has no preview window: build with --features preview".into(),
        ))
    }

    pub fn show(&mut self, _: &Image, _: Tonemap, _: f32) {
        match *self {}
    }

    pub fn wait(self) {
        match self {}
    }
}
