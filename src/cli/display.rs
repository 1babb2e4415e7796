//! `render --display HOST:PORT`: the image streamed to a running tev (the HDR viewer) over
//! its TCP protocol while it renders. The packet formats are tev's (src/Ipc.cpp and
//! include/tev/Ipc.h in Tom94/tev): each packet is its total size in bytes (u32, counting
//! itself), a type byte, then fields little-endian, strings NUL-terminated, bools one byte.
//! vkvcm sends CloseImage (a stale image of the same name goes), CreateImage (R, G, B),
//! then UpdateImageV3 tiles of interleaved RGB per image it sends.
//!
//! A thread of its own sends, so the render never waits on the socket: an image offered
//! while the previous one is still being sent is dropped, and images are offered at most
//! every `--display-every` seconds (from the film read-backs the render makes anyway).
//! The final image is always sent. A viewer that cannot be reached is a warning.

use std::io::Write;
use std::net::{TcpStream, ToSocketAddrs};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};

/// tev's packet types (its `IpcPacket::EType`).
pub const CLOSE_IMAGE: u8 = 2;
pub const CREATE_IMAGE: u8 = 4;
pub const UPDATE_IMAGE_V3: u8 = 6;
/// Tiles of at most this many pixels a side (a 64 x 64 tile is 48 KiB of floats).
const TILE: u32 = 64;

/// One packet being built.
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8) -> Packet {
        Packet(vec![0, 0, 0, 0, kind])
    }
    fn bool(mut self, v: bool) -> Packet {
        self.0.push(v as u8);
        self
    }
    fn str(mut self, s: &str) -> Packet {
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
        self
    }
    fn i32(mut self, v: i32) -> Packet {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn i64(mut self, v: i64) -> Packet {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn f32(mut self, v: f32) -> Packet {
        self.0.extend_from_slice(&v.to_le_bytes());
        self
    }
    fn bytes(mut self) -> Vec<u8> {
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        self.0
    }
}

/// The packets that show `pixels` (`width` x `height`, row 0 at the top) as image `name`.
pub fn update_packets(name: &str, width: u32, height: u32, pixels: &[[f32; 3]]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for ty in (0..height).step_by(TILE as usize) {
        for tx in (0..width).step_by(TILE as usize) {
            let (w, h) = (TILE.min(width - tx), TILE.min(height - ty));
            let mut p = Packet::new(UPDATE_IMAGE_V3).bool(false).str(name).i32(3);
            for c in ["R", "G", "B"] {
                p = p.str(c);
            }
            p = p.i32(tx as i32).i32(ty as i32).i32(w as i32).i32(h as i32);
            // Interleaved RGB: channel c at offset c, stride 3.
            p = p.i64(0).i64(1).i64(2).i64(3).i64(3).i64(3);
            for y in ty..ty + h {
                for x in tx..tx + w {
                    for v in pixels[(y * width + x) as usize] {
                        p = p.f32(v);
                    }
                }
            }
            out.push(p.bytes());
        }
    }
    out
}

/// The packets that replace image `name` by an empty `width` x `height` RGB image.
pub fn create_packets(name: &str, width: u32, height: u32) -> Vec<Vec<u8>> {
    let close = Packet::new(CLOSE_IMAGE).str(name).bytes();
    let mut create = Packet::new(CREATE_IMAGE).bool(true).str(name).i32(width as i32).i32(height as i32).i32(3);
    for c in ["R", "G", "B"] {
        create = create.str(c);
    }
    vec![close, create.bytes()]
}

type Frame = Arc<Vec<[f32; 3]>>;

/// The sending thread and when it was last offered an image.
pub struct Display {
    frames: Option<SyncSender<Frame>>,
    thread: Option<JoinHandle<()>>,
    every: Duration,
    last: Mutex<Option<Instant>>,
}

impl Display {
    /// Starts the thread that connects to `address` and shows image `name`.
    pub fn start(address: &str, name: &str, width: u32, height: u32, every_seconds: f64) -> Result<Display> {
        let addr = address
            .to_socket_addrs()
            .with_context(|| format!("--display {address}: not a HOST:PORT address"))?
            .next()
            .with_context(|| format!("--display {address}: the host has no address"))?;
        let (tx, rx) = sync_channel::<Frame>(1);
        let name = name.to_string();
        let address = address.to_string();
        let thread = std::thread::spawn(move || {
            let connect = TcpStream::connect_timeout(&addr, Duration::from_secs(2));
            let mut socket = match connect {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("warning: --display {address}: cannot connect ({e}); the render goes on without it");
                    return rx.iter().for_each(drop);
                }
            };
            let send = |s: &mut TcpStream, packets: Vec<Vec<u8>>| packets.iter().try_for_each(|p| s.write_all(p));
            if let Err(e) = send(&mut socket, create_packets(&name, width, height)) {
                eprintln!("warning: --display {address}: {e}; the render goes on without it");
                return rx.iter().for_each(drop);
            }
            for frame in rx.iter() {
                if let Err(e) = send(&mut socket, update_packets(&name, width, height, &frame)) {
                    eprintln!("warning: --display {address}: {e}; the render goes on without it");
                    return rx.iter().for_each(drop);
                }
            }
        });
        let every = Duration::from_secs_f64(every_seconds.max(0.0));
        Ok(Display { frames: Some(tx), thread: Some(thread), every, last: Mutex::new(None) })
    }

    /// Offers an image read back during the render: sent if `--display-every` has passed
    /// since the last one and the thread is free, else dropped.
    pub fn offer(&self, pixels: &[[f32; 3]]) {
        let mut last = self.last.lock().unwrap();
        if last.is_some_and(|t| t.elapsed() < self.every) {
            return;
        }
        if let Some(tx) = &self.frames {
            match tx.try_send(Arc::new(pixels.to_vec())) {
                Ok(()) => *last = Some(Instant::now()),
                Err(TrySendError::Full(_)) | Err(TrySendError::Disconnected(_)) => {}
            }
        }
    }

    /// Sends the final image (waiting for the thread) and ends the thread.
    pub fn finish(mut self, pixels: &[[f32; 3]]) {
        if let Some(tx) = self.frames.take() {
            let _ = tx.send(Arc::new(pixels.to_vec()));
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
