//! `vkvcm render --display HOST:PORT` (src/cli/display.rs) against a small TCP server that
//! decodes tev's packets as tev's src/Ipc.cpp reads them (size, type, little-endian fields,
//! NUL-terminated strings, UpdateImageV3's offsets and strides): the image it was sent last
//! must equal the final EXR's R, G, B bit for bit, after a CloseImage and a CreateImage of
//! the output's name and size. No tev is needed. Sabotage tried: tiles sent with x and y
//! swapped (the image differs), and the final image not sent (a 0.2 s --display-every
//! leaves the last frames of the render out: the image differs).

use std::io::Read;
use std::net::TcpListener;
use std::path::Path;

mod common;

/// Reads tev's fields in order.
struct Fields<'a>(&'a [u8]);

impl Fields<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n);
        self.0 = b;
        a
    }
    fn u8(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn i64(&mut self) -> i64 {
        i64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn str(&mut self) -> String {
        let n = self.0.iter().position(|b| *b == 0).expect("a NUL-terminated string");
        let s = String::from_utf8(self.take(n).to_vec()).unwrap();
        self.take(1);
        s
    }
}

/// What the server saw: packet types in order, the image created, its last pixels.
#[derive(Default)]
struct Seen {
    types: Vec<u8>,
    created: Option<(String, i32, i32, Vec<String>)>,
    closed: Vec<String>,
    pixels: Vec<[f32; 3]>,
    updates: usize,
}

fn decode(stream: &[u8]) -> Seen {
    let mut seen = Seen::default();
    let mut rest = stream;
    while !rest.is_empty() {
        let size = u32::from_le_bytes(rest[..4].try_into().unwrap()) as usize;
        let mut f = Fields(&rest[4..size]);
        rest = &rest[size..];
        let ty = f.u8();
        seen.types.push(ty);
        match ty {
            2 => seen.closed.push(f.str()),
            4 => {
                let _grab = f.u8();
                let name = f.str();
                let (w, h, n) = (f.i32(), f.i32(), f.i32());
                let names = (0..n).map(|_| f.str()).collect();
                seen.pixels = vec![[f32::NAN; 3]; (w * h) as usize];
                seen.created = Some((name, w, h, names));
            }
            6 => {
                let _grab = f.u8();
                let name = f.str();
                let (_, w, _, _) = seen.created.as_ref().expect("an update before the image was created");
                let w = *w;
                assert_eq!(&name, &seen.created.as_ref().unwrap().0);
                let n = f.i32() as usize;
                let channels: Vec<String> = (0..n).map(|_| f.str()).collect();
                assert_eq!(channels, ["R", "G", "B"]);
                let (x, y, tw, th) = (f.i32(), f.i32(), f.i32(), f.i32());
                let offsets: Vec<i64> = (0..n).map(|_| f.i64()).collect();
                let strides: Vec<i64> = (0..n).map(|_| f.i64()).collect();
                let data: Vec<f32> = std::iter::from_fn(|| (!f.0.is_empty()).then(|| f.f32())).collect();
                for py in 0..th {
                    for px in 0..tw {
                        let i = (py * tw + px) as i64;
                        let v = [0, 1, 2].map(|c| data[(offsets[c] + i * strides[c]) as usize]);
                        seen.pixels[((y + py) * w + x + px) as usize] = v;
                    }
                }
                seen.updates += 1;
            }
            other => panic!("unexpected packet type {other}"),
        }
    }
    seen
}

#[test]
fn display_streams_the_final_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        s.read_to_end(&mut bytes).unwrap();
        bytes
    });
    // 70 x 50: tiles of 64 and of the rest in both directions.
    let o = common::vkvcm_in(d)
        .args(["render", "glm_c", "-a", "pt", "--width", "70", "--height", "50", "-i", "24", "-q"])
        .args(["-o", "shown.exr", "--display", &format!("127.0.0.1:{port}"), "--display-every", "0.2"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("warning"), "{err}");
    let seen = decode(&server.join().unwrap());
    assert_eq!(&seen.types[..2], &[2, 4], "CloseImage then CreateImage first");
    assert_eq!(seen.closed, ["shown.exr"]);
    let (name, w, h, names) = seen.created.clone().unwrap();
    assert_eq!((name.as_str(), w, h), ("shown.exr", 70, 50));
    assert_eq!(names, ["R", "G", "B"]);
    assert!(seen.updates >= 4, "at least the final image's four tiles: {}", seen.updates);
    let (img, _, _) = vkvcm::image::read_exr_channels(&d.join("shown.exr")).unwrap();
    let differ = img.data.iter().zip(&seen.pixels).filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits)).count();
    assert_eq!(differ, 0, "{differ} pixels differ from the final EXR's");
}

#[test]
fn display_without_a_viewer_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    // A port nothing listens on: bound, then closed.
    let port = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let o = common::vkvcm_in(dir.path())
        .args(["render", "glm_c", "-a", "el", "--width", "8", "--height", "8", "-i", "1", "-q"])
        .args(["-o", "x.exr", "--display", &format!("127.0.0.1:{port}")])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning: --display") && err.contains("cannot connect"), "{err}");
    assert!(Path::new(&dir.path().join("x.exr")).is_file());
}
