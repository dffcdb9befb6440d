//! `shmgen watch` and `shmgen check` end to end, through the built binary: edits, broken saves
//! and their fixes, editors' save patterns (delete and recreate, write and rename), imported
//! modules, Ctrl-C, the sheet written by --once and the loopback web page.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

mod common;

const BIN: &str = env!("CARGO_BIN_EXE_shmgen");

/// Generous for a busy 2-core machine; waits poll often, so passing tests stay fast.
const WAIT: Duration = Duration::from_secs(20);
const POLL: Duration = Duration::from_millis(20);

/// Two structures (so instance ids differ), one of them with two parts, built by a module
/// next to the recipe. Pure blue background and no anti-aliasing: an RGB pixel is background
/// exactly when no surface is there.
const RECIPE: &str = r#"import "piece" as piece;

dataset(#{
    name: "watched",
    seed: 1,
    samples: 2,
    views: 2,
    outputs: ["rgb", "depth", "mask", "parts", "instances"],
    background: [0.0, 0.0, 1.0],
    antialias: false,
    camera: #{ width: 64, height: 48, pitch: [deg(10), deg(60)] },
    scene: |rng| [
        assembly("block", [piece::block(rng.uniform(0.8, 1.2)), shape::box(0.3, 0.3, 0.3).translate(0.0, 0.0, 0.3).part("cap")])
            .colour([0.8, 0.3, 0.2]),
        assembly("post", [shape::box(0.2, 0.2, 0.8).translate(0.9, 0.0, 0.0)]).colour([0.3, 0.7, 0.3]),
    ],
});
"#;

const PIECE: &str = "fn block(size) { shape::box(size, 0.5 * size, 0.3 * size) }\n";

/// A folder with the recipe and its module.
fn project() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("piece.rhai"), PIECE).unwrap();
    let recipe = dir.path().join("recipe.rhai");
    std::fs::write(&recipe, RECIPE).unwrap();
    (dir, recipe)
}

fn preview_of(recipe: &Path) -> PathBuf {
    recipe.with_file_name("recipe.preview.png")
}

/// `RECIPE` with the first structure's colour changed.
fn recoloured(rgb: &str) -> String {
    let text = RECIPE.replace("[0.8, 0.3, 0.2]", rgb);
    assert_ne!(text, RECIPE);
    text
}

fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(start.elapsed() < WAIT, "timed out waiting for {what}");
        std::thread::sleep(POLL);
    }
}

/// A running `shmgen watch`, killed when dropped (also when a test fails).
struct Watch {
    child: Child,
    stdout: Arc<Mutex<String>>,
    stderr: Arc<Mutex<String>>,
}

impl Watch {
    fn start(recipe: &Path, extra: &[&str]) -> Watch {
        Watch::spawn(Command::new(BIN).arg("watch").arg(recipe).args(extra))
    }

    fn spawn(command: &mut Command) -> Watch {
        let mut child = command
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdout = collect(child.stdout.take().unwrap());
        let stderr = collect(child.stderr.take().unwrap());
        Watch {
            child,
            stdout,
            stderr,
        }
    }

    fn stdout(&self) -> String {
        self.stdout.lock().unwrap().clone()
    }

    fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    fn previews(&self) -> usize {
        self.stdout()
            .lines()
            .filter(|l| l.starts_with("preview:"))
            .count()
    }

    /// Waits for preview number `n` (counting from 1) and returns the sheet's bytes.
    fn wait_for_preview(&self, n: usize, file: &Path) -> Vec<u8> {
        wait_until(&format!("preview {n}"), || self.previews() >= n);
        assert_eq!(
            self.previews(),
            n,
            "one preview per change:\n{}",
            self.stdout()
        );
        std::fs::read(file).unwrap()
    }

    fn assert_alive(&mut self) {
        assert!(
            self.child.try_wait().unwrap().is_none(),
            "the watcher exited:\n{}\n{}",
            self.stdout(),
            self.stderr()
        );
    }
}

impl Watch {
    /// Saves `TYPO_IN_SAMPLE_4` with its typo fixed over `recipe` (the watcher's second
    /// sheet) and waits for the scene pass over its 6 samples to pass.
    fn save_the_fix(&self, recipe: &Path) {
        std::fs::write(recipe, TYPO_IN_SAMPLE_4.replace("materail", "material")).unwrap();
        self.wait_for_preview(2, &preview_of(recipe));
        wait_until("the pass over the fixed recipe", || {
            self.stdout()
                .contains("scenes: all 6 samples drawn without error")
        });
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Gathers a child's output as it comes, so the test can look at it while the child runs.
fn collect(mut pipe: impl Read + Send + 'static) -> Arc<Mutex<String>> {
    let text = Arc::new(Mutex::new(String::new()));
    let sink = text.clone();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = pipe.read(&mut buf) {
            if n == 0 {
                break;
            }
            sink.lock()
                .unwrap()
                .push_str(&String::from_utf8_lossy(&buf[..n]));
        }
    });
    text
}

#[test]
fn an_edit_gives_a_new_preview() {
    let (_dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &[]);
    let first = watch.wait_for_preview(1, &sheet);
    std::fs::write(&recipe, recoloured("[0.2, 0.3, 0.8]")).unwrap();
    let second = watch.wait_for_preview(2, &sheet);
    assert_ne!(first, second, "the colour change shows");
}

#[test]
fn a_broken_save_keeps_the_last_preview_and_a_fix_recovers() {
    let (_dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let mut watch = Watch::start(&recipe, &[]);
    let good = watch.wait_for_preview(1, &sheet);

    let broken = RECIPE.replace("    seed: 1,", "    seed: 1 1,");
    let line = broken
        .lines()
        .position(|l| l.contains("seed: 1 1"))
        .unwrap()
        + 1;
    std::fs::write(&recipe, &broken).unwrap();
    wait_until("the error", || {
        watch.stderr().contains("keeping the last good preview")
    });
    let stderr = watch.stderr();
    let location = format!("recipe.rhai:{line}:");
    assert!(stderr.contains(&location), "{location} in:\n{stderr}");
    assert!(
        stderr.contains("    seed: 1 1,"),
        "the source line in:\n{stderr}"
    );
    watch.assert_alive();
    assert_eq!(
        std::fs::read(&sheet).unwrap(),
        good,
        "the last good preview stays"
    );
    assert_eq!(watch.previews(), 1);

    std::fs::write(&recipe, recoloured("[0.9, 0.9, 0.2]")).unwrap();
    let fixed = watch.wait_for_preview(2, &sheet);
    assert_ne!(fixed, good);
    watch.assert_alive();
}

#[test]
fn delete_and_recreate_and_write_and_rename_both_reload() {
    let (dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &[]);
    let first = watch.wait_for_preview(1, &sheet);

    std::fs::remove_file(&recipe).unwrap();
    std::fs::write(&recipe, recoloured("[0.2, 0.8, 0.8]")).unwrap();
    wait_until("a preview after delete and recreate", || {
        std::fs::read(&sheet).unwrap() != first
    });
    let recreated = std::fs::read(&sheet).unwrap();

    // An editor's atomic save: a temporary file renamed over the recipe.
    let tmp = dir.path().join(".recipe.rhai.tmp");
    std::fs::write(&tmp, recoloured("[0.9, 0.6, 0.1]")).unwrap();
    std::fs::rename(&tmp, &recipe).unwrap();
    wait_until("a preview after write and rename", || {
        std::fs::read(&sheet).unwrap() != recreated
    });
}

/// Edits the module the recipe imports, next to the recipe or in the standard-library folder,
/// and expects a new preview. The standard-library folder is not the recipe's: only the list
/// of files the recipe used can tell the watcher to look there.
fn editing_the_module_reloads(in_stdlib: bool) {
    let (dir, recipe) = project();
    let stdlib = tempfile::tempdir().unwrap();
    let module = match in_stdlib {
        true => stdlib.path().join("piece.rhai"),
        false => dir.path().join("piece.rhai"),
    };
    std::fs::rename(dir.path().join("piece.rhai"), &module).unwrap();
    let sheet = preview_of(&recipe);
    let watch = Watch::spawn(
        Command::new(BIN)
            .arg("watch")
            .arg(&recipe)
            .env("SHMGEN_STDLIB", stdlib.path()),
    );
    let first = watch.wait_for_preview(1, &sheet);
    std::fs::write(&module, PIECE.replace("0.3 * size", "0.6 * size")).unwrap();
    let second = watch.wait_for_preview(2, &sheet);
    assert_ne!(first, second, "the taller block shows");
}

#[test]
fn editing_an_imported_module_reloads() {
    editing_the_module_reloads(false);
}

#[test]
fn editing_a_module_in_another_folder_reloads() {
    editing_the_module_reloads(true);
}

/// A 4×4 PNG of one colour.
fn write_png(path: &Path, rgb: [u8; 3]) {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 4, 4);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&rgb.repeat(16)).unwrap();
    writer.finish().unwrap();
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn a_texture_dropped_in_and_then_edited_reloads() {
    // The block's prompt "steel" takes textures/steel.png as its texture once it exists.
    let (dir, recipe) = project();
    std::fs::write(
        &recipe,
        RECIPE.replace(".colour([0.8, 0.3, 0.2])", ".material(\"steel\")"),
    )
    .unwrap();
    let textures = dir.path().join("textures");
    std::fs::create_dir(&textures).unwrap();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &[]);
    let procedural = watch.wait_for_preview(1, &sheet);
    write_png(&textures.join("steel.png"), [200, 30, 30]);
    let red = watch.wait_for_preview(2, &sheet);
    assert_ne!(procedural, red, "the image replaces the procedural texture");
    write_png(&textures.join("steel.png"), [30, 200, 30]);
    let green = watch.wait_for_preview(3, &sheet);
    assert_ne!(red, green, "the edited image shows");
}

#[test]
fn saving_the_same_content_or_touching_other_files_does_not_reload() {
    let (dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &[]);
    watch.wait_for_preview(1, &sheet);
    // A no-op save, a note and an editor's backup: none changes the preview...
    std::fs::write(&recipe, RECIPE).unwrap();
    std::fs::write(dir.path().join("notes.txt"), "x").unwrap();
    std::fs::write(dir.path().join("recipe.rhai~"), "x").unwrap();
    // ...and a real edit afterwards is the second preview, not the third.
    std::thread::sleep(Duration::from_millis(500));
    std::fs::write(&recipe, recoloured("[0.5, 0.5, 0.5]")).unwrap();
    watch.wait_for_preview(2, &sheet);
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(watch.previews(), 2, "{}", watch.stdout());
}

#[test]
fn ctrl_c_exits_cleanly() {
    let (dir, recipe) = project();
    let mut watch = Watch::start(&recipe, &[]);
    watch.wait_for_preview(1, &preview_of(&recipe));
    let status = Command::new("kill")
        .args(["-INT", &watch.child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let start = Instant::now();
    let exit = loop {
        if let Some(exit) = watch.child.try_wait().unwrap() {
            break exit;
        }
        assert!(start.elapsed() < WAIT, "still running after Ctrl-C");
        std::thread::sleep(POLL);
    };
    assert!(exit.success(), "{exit:?}");
    wait_until("the goodbye", || watch.stdout().contains("stopped"));
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["piece.rhai", "recipe.preview.png", "recipe.rhai"]);
}

#[test]
fn once_writes_an_rgb_png_sheet() {
    // What each column and row of the sheet shows is tested with the sheet
    // (src/preview/sheet.rs, tests/sheet.rs); here only that --once writes one to --out.
    let (dir, recipe) = project();
    let out = dir.path().join("sheet.png");
    let output = Command::new(BIN)
        .arg("watch")
        .arg(&recipe)
        .args(["--once", "--size", "32", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(output.status.success(), "{output:?}");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut data = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut data).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert!(info.width > 32 && info.height > 24, "{info:?}");
}

#[test]
fn once_fails_on_a_broken_recipe() {
    let (_dir, recipe) = project();
    std::fs::write(&recipe, RECIPE.replace("samples: 2,", "samples: 2,,")).unwrap();
    let output = Command::new(BIN)
        .arg("watch")
        .arg(&recipe)
        .arg("--once")
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("recipe.rhai:6:"), "{stderr}");
    assert!(!preview_of(&recipe).exists());
}

#[test]
fn watching_a_missing_recipe_fails_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let output = Command::new(BIN)
        .arg("watch")
        .arg(dir.path().join("typo.rhai"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("typo.rhai: no such recipe file"));
}

fn check(recipe: &Path) -> Output {
    Command::new(BIN).arg("check").arg(recipe).output().unwrap()
}

#[test]
fn check_reports_counts_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let recipe = dir.path().join("box.rhai");
    let text = r#"dataset(#{
    name: "box",
    seed: 1,
    samples: 3,
    views: 2,
    camera: #{ width: 64, height: 48 },
    scene: |rng| assembly("block", [shape::box(1.0, 0.5, 0.3)]),
});
"#;
    std::fs::write(&recipe, text).unwrap();
    let output = check(&recipe);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{output:?}");
    assert!(stdout.contains("3 samples × 2 views"), "{stdout}");
    // A closed box shares its 8 corners among 6 faces of 2 triangles each
    // (Euler: 8 − 18 + 12 = 2).
    assert!(
        stdout.contains("assembly \"block\": 3, vertices 8 / 8 / 8, triangles 12 / 12 / 12"),
        "{stdout}"
    );
    assert!(stdout.contains("estimate for all 3 samples"), "{stdout}");

    std::fs::write(&recipe, text.replace("samples: 3,", "samples: 3 +,")).unwrap();
    let output = check(&recipe);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(stderr.contains("box.rhai:4:"), "{stderr}");
    assert!(stderr.contains("samples: 3 +,"), "{stderr}");
}

/// The port of the URL `shmgen watch --serve` printed, which must be on 127.0.0.1.
fn served_port(watch: &Watch) -> u16 {
    let stdout = watch.stdout();
    let url = stdout
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("no URL in:\n{stdout}"));
    url.strip_prefix("http://127.0.0.1:")
        .and_then(|rest| rest.strip_suffix('/'))
        .unwrap_or_else(|| panic!("{url} is not on 127.0.0.1"))
        .parse()
        .unwrap()
}

/// GET `path` from a local server: (status line, body).
/// The numbers in `text`, in order (digits and points; "0–7" gives 0 and 7).
fn numbers_in(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter_map(|word| word.trim_matches('.').parse().ok())
        .collect()
}

/// `shmgen check` succeeds on every recipe in `scripts/` (a ground, drawn supports,
/// assemblies, augmentations…) and reports what the recipe declares, consistently: samples ×
/// views = views, the structures of the first samples with sizes in order (min ≤ median ≤
/// max, none empty), a timed run and the estimate for all samples. A recipe with a ground
/// once panicked here (the ground's triangles were counted as a structure's).
#[test]
fn check_succeeds_on_every_bundled_recipe() {
    let recipes = common::bundled_rhai("scripts");
    assert!(recipes.len() >= 8, "{recipes:?}");
    for recipe in &recipes {
        let output = Command::new(BIN)
            .arg("check")
            .arg(recipe)
            .args(["--threads", "1"])
            .output()
            .unwrap();
        let (stdout, stderr) = (
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr),
        );
        let name = recipe.display();
        assert!(output.status.success(), "{name}: {stderr}");
        let lines: Vec<&str> = stdout.lines().collect();
        assert!(
            lines[0].starts_with(&format!("{name}: dataset ")),
            "{stdout}"
        );
        let counts = numbers_in(lines[1]);
        let (samples, views) = (counts[0], counts[1]);
        assert_eq!(samples * views, counts[2], "{name}: {}", lines[1]);
        let header = numbers_in(lines[2]);
        assert_eq!(
            header[..2],
            [0.0, samples.min(8.0) - 1.0],
            "{name}: {}",
            lines[2]
        );
        let kinds: Vec<&str> = lines
            .iter()
            .copied()
            .filter(|l| l.contains(", vertices "))
            .collect();
        assert!(!kinds.is_empty(), "{name}: no structure in\n{stdout}");
        for kind in kinds {
            let sizes = numbers_in(kind.split(", vertices ").nth(1).unwrap());
            for spread in [&sizes[0..3], &sizes[3..6]] {
                assert!(
                    spread[0] > 0.0 && spread[0] <= spread[1] && spread[1] <= spread[2],
                    "{name}: {kind}"
                );
            }
        }
        assert!(
            stdout.contains("  timed run: 1 sample (")
                && stdout.contains(&format!(
                    "  estimate for all {samples} samples on 1 thread: "
                )),
            "{name}: {stdout}"
        );
    }
}

fn get(port: u16, path: &str) -> (String, Vec<u8>) {
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    // A server that never answers fails the test instead of hanging it.
    stream.set_read_timeout(Some(WAIT)).unwrap();
    write!(
        stream,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut response = Vec::new();
    stream.read_to_end(&mut response).unwrap();
    let split = response.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&response[..split]).into_owned();
    assert!(head.contains("Cache-Control: no-store"), "{head}");
    let status = head.lines().next().unwrap().to_string();
    (status, response[split + 4..].to_vec())
}

#[test]
fn the_preview_is_served_on_loopback() {
    let (_dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &["--serve", "0"]);
    let png = watch.wait_for_preview(1, &sheet);
    let port = served_port(&watch);

    let (status, page) = get(port, "/");
    assert!(status.contains("200"), "{status}");
    assert!(String::from_utf8_lossy(&page).contains("<html"));
    let (status, served) = get(port, "/preview.png?n=1");
    assert!(status.contains("200"), "{status}");
    assert_eq!(served, png);

    std::fs::write(&recipe, RECIPE.replace("views: 2,", "views: 2,,")).unwrap();
    wait_until("the error on the page", || {
        String::from_utf8_lossy(&get(port, "/state").1).contains("recipe.rhai:")
    });
    assert_eq!(
        get(port, "/preview.png").1,
        png,
        "the last good sheet stays"
    );
}

/// Threads of process `pid`, from Linux's /proc/PID/status (the kernel's own count).
fn threads(pid: u32) -> usize {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .unwrap_or_else(|| panic!("no Threads line in:\n{status}"))
        .trim()
        .parse()
        .unwrap()
}

#[test]
fn idle_and_slow_clients_neither_add_threads_nor_keep_a_request_out() {
    let (_dir, recipe) = project();
    let sheet = preview_of(&recipe);
    let watch = Watch::start(&recipe, &["--serve", "0"]);
    watch.wait_for_preview(1, &sheet);
    let port = served_port(&watch);
    let pid = watch.child.id();
    // The background scene pass has its own threads while it runs; count without them.
    wait_until("the scene pass", || watch.stdout().contains("scenes: all"));
    let before = threads(pid);

    // 300 clients hold connections: half say nothing, half start a request and stall.
    let clients: Vec<TcpStream> = (0..300)
        .map(|i| {
            let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
            if i % 2 == 1 {
                stream.write_all(b"GET / HTTP/1.1\r\nHost: 127").unwrap();
            }
            stream
        })
        .collect();
    let start = Instant::now();
    let (status, page) = get(port, "/");
    assert!(status.contains("200"), "{status}");
    assert!(String::from_utf8_lossy(&page).contains("<html"));
    assert!(
        start.elapsed() < Duration::from_secs(2),
        "a request waited {:?} behind idle clients",
        start.elapsed()
    );
    let during = threads(pid);
    assert!(
        during <= before + 1,
        "{before} threads before 300 idle clients, {during} with them"
    );

    // The server let the oldest idle client go rather than hold all 300.
    let mut first = &clients[0];
    first
        .set_read_timeout(Some(Duration::from_secs(2)))
        .unwrap();
    match first.read(&mut [0u8; 16]) {
        Ok(0) => {}
        Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => {}
        other => panic!("the oldest idle client is still held: {other:?}"),
    }
    drop(clients);

    // A request head of 16 KiB (the server's limit, sent whole so that nothing unread makes
    // the close a reset) without its end is refused, not buffered further.
    let mut stream = TcpStream::connect(("127.0.0.1", port)).unwrap();
    stream.set_read_timeout(Some(WAIT)).unwrap();
    let mut long = b"GET / HTTP/1.1\r\nX-Pad: ".to_vec();
    long.resize(16 * 1024, b'a');
    stream.write_all(&long).unwrap();
    let mut response = Vec::new();
    stream.read_to_end(&mut response).unwrap();
    let response = String::from_utf8_lossy(&response);
    assert!(response.starts_with("HTTP/1.1 431"), "{response}");
}

/// Six samples; only sample 4 (4 % 5 == 4) takes the branch with the misspelt method, so the
/// sheet (samples 0–1) renders and only a pass over every sample can find it.
const TYPO_IN_SAMPLE_4: &str = r#"dataset(#{
    name: "rare branch",
    seed: 1,
    samples: 6,
    views: 1,
    camera: #{ width: 32, height: 24 },
    scene: |rng| {
        let b = beam(#{ length: 2.0, width: 0.2, height: 0.3 }).simply_supported();
        if rng.sample % 5 == 4 {
            b = b.materail("steel");
        }
        b
    },
});
"#;

/// A folder with `TYPO_IN_SAMPLE_4` changed to `samples` samples, the misspelt branch taken
/// when `taken` (a condition on `rng.sample`): the folder, the recipe and its text.
fn typo_recipe(samples: u64, taken: &str) -> (tempfile::TempDir, PathBuf, String) {
    let dir = tempfile::tempdir().unwrap();
    let recipe = dir.path().join("recipe.rhai");
    let text = TYPO_IN_SAMPLE_4
        .replace("samples: 6", &format!("samples: {samples}"))
        .replace("rng.sample % 5 == 4", taken);
    std::fs::write(&recipe, &text).unwrap();
    (dir, recipe, text)
}

/// Line and column (from 1) of the first `needle` in `text`.
fn line_col(text: &str, needle: &str) -> (usize, usize) {
    text.lines()
        .enumerate()
        .find_map(|(i, line)| line.find(needle).map(|c| (i + 1, c + 1)))
        .unwrap_or_else(|| panic!("{needle} not in the text"))
}

#[test]
fn the_scene_pass_finds_an_error_in_a_sample_the_sheet_does_not_show_and_a_fix_clears_it() {
    let (_dir, recipe, _) = typo_recipe(6, "rng.sample % 5 == 4");
    let watch = Watch::start(&recipe, &["--samples", "2", "--serve", "0"]);
    watch.wait_for_preview(1, &preview_of(&recipe));
    let port = served_port(&watch);

    wait_until("the scene pass's error", || {
        watch
            .stderr()
            .contains("scenes: the scene of sample 4 fails")
    });
    let stderr = watch.stderr();
    let (line, col) = line_col(TYPO_IN_SAMPLE_4, "materail");
    for expected in [
        format!("recipe.rhai:{line}:{col}"),
        "while drawing the scene of sample 4".to_string(),
        "did you mean `material`?".to_string(),
    ] {
        assert!(stderr.contains(&expected), "{expected} in:\n{stderr}");
    }
    let state = String::from_utf8_lossy(&get(port, "/state").1).into_owned();
    assert!(
        state.contains("sample 4 fails") && state.contains(&format!("recipe.rhai:{line}:{col}")),
        "the page shows it: {state}"
    );

    watch.save_the_fix(&recipe);
    let state: serde_json::Value = serde_json::from_slice(&get(port, "/state").1).unwrap();
    assert!(state["error"].is_null(), "the error is gone: {state}");
    assert!(
        state["scenes"]
            .as_str()
            .is_some_and(|s| s.contains("all 6 samples drawn without error")),
        "{state}"
    );
}

/// `check` draws in full only the first 8 samples; its scene pass still finds an error in the
/// scene of sample 10, and says when every scene passed.
#[test]
fn check_draws_every_sample_s_scene() {
    let (_dir, recipe, text) = typo_recipe(12, "rng.sample == 10");
    let output = check(&recipe);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    let (line, col) = line_col(&text, "materail");
    for expected in [
        format!("recipe.rhai:{line}:{col}"),
        "while drawing the scene of sample 10".to_string(),
    ] {
        assert!(stderr.contains(&expected), "{expected} in:\n{stderr}");
    }

    std::fs::write(&recipe, text.replace("materail", "material")).unwrap();
    let output = check(&recipe);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{output:?}");
    assert!(
        stdout.contains("scenes: all 12 samples drawn without error"),
        "{stdout}"
    );
}

/// Names of the threads of process `pid` (Linux's /proc/PID/task/*/comm).
fn thread_names(pid: u32) -> Vec<String> {
    std::fs::read_dir(format!("/proc/{pid}/task"))
        .map(|tasks| {
            tasks
                .flatten()
                .filter_map(|t| std::fs::read_to_string(t.path().join("comm")).ok())
                .map(|name| name.trim().to_string())
                .collect()
        })
        .unwrap_or_default()
}

/// A save abandons the running pass: with a million samples it would run for minutes, but
/// once the fixed recipe's pass has reported, no pass thread is left, and the abandoned pass
/// never reports.
#[test]
fn a_new_save_abandons_the_running_scene_pass() {
    let (_dir, recipe, _) = typo_recipe(1_000_000, "rng.sample == 999999");
    let watch = Watch::start(&recipe, &["--samples", "1"]);
    watch.wait_for_preview(1, &preview_of(&recipe));
    let pid = watch.child.id();
    let passes = || {
        thread_names(pid)
            .iter()
            .filter(|name| name.as_str() == "scene pass")
            .count()
    };
    wait_until("the pass to run", || passes() > 0);

    watch.save_the_fix(&recipe);
    let start = Instant::now();
    wait_until("the abandoned pass to stop", || passes() == 0);
    assert!(
        start.elapsed() < Duration::from_secs(5),
        "{:?}",
        start.elapsed()
    );
    let said = format!("{}{}", watch.stdout(), watch.stderr());
    assert!(
        !said.contains("1000000 samples") && !said.contains("sample 999999"),
        "{said}"
    );
}
