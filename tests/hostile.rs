//! Hostile recipes and recipe folders: what a recipe may read (symlinks, special files, sizes),
//! the limits on what its script may do (waiting, memory, nesting, output), and the clarity of
//! the errors it gets. Every run here must end quickly, with a clear message, and show nothing
//! of a file the recipe may not read.

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

mod common;

use common::{ok, read_json, run_limited, stderr, write};

/// A scene that renders in a blink.
const SCENE: &str = "scene: |rng| beam(#{ length: 2.0, width: 0.2, height: 0.3 })";

/// A whole recipe: `before` (statements), then a dataset with `options` and `SCENE`.
fn recipe(before: &str, options: &str) -> String {
    format!(
        "{before}\ndataset(#{{ samples: 1, camera: #{{ width: 16, height: 16 }}, {options} {SCENE} }})\n"
    )
}

/// What a file outside the recipe folder holds; it must never appear in a message.
const SECRET: &str = "let secret_token_3141 = 1;\nsecret_token_3141 +;\n";

/// `shmgen ARGS...`, killed and failed if it runs longer than `limit`.
fn run_within(limit: Duration, args: &[&std::ffi::OsStr]) -> Output {
    let (output, finished) = run_limited(limit, args);
    assert!(
        finished,
        "shmgen {args:?} still ran after {limit:?}:\n{}",
        clip(&stderr(&output))
    );
    output
}

/// The start of a long text, for a failure message.
fn clip(text: &str) -> String {
    text.chars().take(4000).collect()
}

/// `shmgen run RECIPE --out DIR/out --quiet EXTRA...` into a fresh `DIR/out`, within 60 s.
fn run(recipe: &Path, extra: &[&str]) -> Output {
    let out = recipe.parent().unwrap().join("out");
    if out.exists() {
        std::fs::remove_dir_all(&out).unwrap();
    }
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "run".as_ref(),
        recipe.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--quiet".as_ref(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    run_within(Duration::from_secs(60), &args)
}

/// The run must fail, naming every fragment, never showing `SECRET`, and writing nothing.
fn refused(recipe: &Path, extra: &[&str], fragments: &[&str]) -> String {
    let output = run(recipe, extra);
    let text = stderr(&output);
    assert!(!output.status.success(), "must fail:\n{text}");
    for fragment in fragments {
        assert!(text.contains(fragment), "expected `{fragment}` in:\n{text}");
    }
    assert!(
        !text.contains("secret_token"),
        "a file outside the recipe folder was shown:\n{text}"
    );
    assert!(!recipe.parent().unwrap().join("out").exists());
    text
}

/// A tiny RGB PNG.
fn png(width: u32, height: u32) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().unwrap();
    writer
        .write_image_data(&vec![128; (width * height * 3) as usize])
        .unwrap();
    writer.finish().unwrap();
    out
}

fn tetra() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/tetra.obj"))
        .unwrap()
}

/// A recipe folder `dir/recipe` and, next to it, a folder `dir/outside` holding a secret
/// module, a mesh, an image and a folder of images.
fn folders(dir: &Path) -> (PathBuf, PathBuf) {
    let (inside, outside) = (dir.join("recipe"), dir.join("outside"));
    write(&outside, "secret.rhai", SECRET);
    write(&outside, "tetra.obj", tetra());
    write(&outside, "tetra.bin", [0u8; 72]);
    write(&outside, "photo.png", png(4, 4));
    write(&outside, "photos/a.png", png(4, 4));
    std::fs::create_dir_all(&inside).unwrap();
    (inside, outside)
}

fn mkfifo(path: &Path) {
    assert!(
        Command::new("mkfifo").arg(path).status().unwrap().success(),
        "mkfifo"
    );
}

#[test]
fn symlinks_out_of_the_recipe_folder_are_refused_for_every_kind_of_file() {
    let dir = tempfile::tempdir().unwrap();
    let (inside, outside) = folders(dir.path());
    let mesh_scene = "scene: |rng| assembly(\"a\", [shape::mesh(\"m.obj\")])";
    let link = |from: &str, to: &str| symlink(outside.join(from), inside.join(to)).unwrap();

    // A module: its text is never shown, not even as the line of a syntax error.
    link("secret.rhai", "secret.rhai");
    let r = write(&inside, "r.rhai", recipe("import \"secret\" as s;", ""));
    refused(
        &r,
        &[],
        &[
            "import \"secret\"",
            "outside the recipe's folder",
            "r.rhai:1:",
        ],
    );

    // A module in a linked folder.
    std::fs::remove_file(inside.join("secret.rhai")).unwrap();
    symlink(&outside, inside.join("lib")).unwrap();
    let r = write(&inside, "r.rhai", recipe("import \"lib/secret\" as s;", ""));
    refused(&r, &[], &["outside the recipe's folder"]);

    // A mesh.
    link("tetra.obj", "m.obj");
    let r = write(
        &inside,
        "r.rhai",
        format!("dataset(#{{ samples: 1, camera: #{{ width: 16, height: 16 }}, {mesh_scene} }})"),
    );
    refused(
        &r,
        &[],
        &["shape::mesh", "m.obj", "outside the recipe's folder"],
    );

    // A glTF inside whose buffer file is outside.
    std::fs::remove_file(inside.join("m.obj")).unwrap();
    let gltf = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/tetra.gltf"),
    )
    .unwrap();
    let start = gltf.find("data:application").unwrap();
    let end = start + gltf[start..].find('"').unwrap();
    let escaping = format!("{}../outside/tetra.bin{}", &gltf[..start], &gltf[end..]);
    write(&inside, "m.gltf", escaping);
    let r = write(
        &inside,
        "r.rhai",
        format!(
            "dataset(#{{ samples: 1, camera: #{{ width: 16, height: 16 }}, {} }})",
            mesh_scene.replace("m.obj", "m.gltf")
        ),
    );
    refused(
        &r,
        &[],
        &["m.gltf: buffer 0", "outside the recipe's folder"],
    );

    // A texture named explicitly, and one found by its prompt's name.
    link("photo.png", "t.png");
    let textured = |options: &str| {
        format!(
            "dataset(#{{ samples: 1, camera: #{{ width: 16, height: 16 }}, scene: |rng| beam(#{{ length: 2.0, width: 0.2, height: 0.3 }}).material(\"rusty steel\"{options}) }})"
        )
    };
    let r = write(&inside, "r.rhai", textured(", #{ texture: \"t.png\" }"));
    refused(
        &r,
        &[],
        &["material options.texture", "outside the recipe's folder"],
    );
    std::fs::create_dir_all(inside.join("textures")).unwrap();
    link("photo.png", "textures/rusty-steel.png");
    let r = write(&inside, "r.rhai", textured(""));
    refused(&r, &[], &["rusty-steel.png", "outside the recipe's folder"]);

    // A background folder that is a link, and a real folder of links.
    link("photos", "bg");
    let r = write(
        &inside,
        "r.rhai",
        recipe("", "background: #{ images: \"bg\" },"),
    );
    refused(
        &r,
        &[],
        &["dataset.background.images", "outside the recipe's folder"],
    );
    std::fs::create_dir_all(inside.join("bg2")).unwrap();
    link("photo.png", "bg2/a.png");
    let r = write(
        &inside,
        "r.rhai",
        recipe("", "background: #{ images: \"bg2\" },"),
    );
    refused(&r, &[], &["bg2/a.png", "outside the recipe's folder"]);
}

#[test]
fn links_that_stay_inside_the_recipe_folder_still_work() {
    let dir = tempfile::tempdir().unwrap();
    let inside = dir.path().join("recipe");
    write(&inside, "lib/real.rhai", "fn height() { 0.3 }\n");
    symlink(inside.join("lib/real.rhai"), inside.join("alias.rhai")).unwrap();
    write(&inside, "meshes/tetra.obj", tetra());
    symlink(inside.join("meshes/tetra.obj"), inside.join("m.obj")).unwrap();
    write(&inside, "photos/a.png", png(4, 4));
    symlink(inside.join("photos"), inside.join("bg")).unwrap();
    let r = write(
        &inside,
        "r.rhai",
        "import \"alias\" as a;\ndataset(#{ samples: 1, camera: #{ width: 16, height: 16 }, background: #{ images: \"bg\" },\n  scene: |rng| [beam(#{ length: 2.0, width: 0.2, height: a::height() }), assembly(\"m\", [shape::mesh(\"m.obj\")])] })\n",
    );
    ok(run(&r, &[]));
}

#[test]
fn special_and_oversized_files_are_refused_without_waiting_or_reading_them() {
    let dir = tempfile::tempdir().unwrap();
    let inside = dir.path().join("recipe");
    std::fs::create_dir_all(inside.join("bg")).unwrap();
    std::fs::create_dir_all(inside.join("textures")).unwrap();
    // Nothing ever writes to these fifos: opening one to read would wait for ever.
    for fifo in [
        "f.rhai",
        "m.obj",
        "t.png",
        "bg/a.png",
        "textures/rusty-steel.png",
    ] {
        mkfifo(&inside.join(fifo));
    }
    let special = "special file (fifo, device or socket)";
    let r = write(&inside, "r.rhai", recipe("import \"f\" as f;", ""));
    refused(&r, &[], &["import \"f\"", special]);
    let r = write(
        &inside,
        "r.rhai",
        "dataset(#{ samples: 1, scene: |rng| assembly(\"a\", [shape::mesh(\"m.obj\")]) })",
    );
    refused(&r, &[], &["m.obj", special]);
    let r = write(
        &inside,
        "r.rhai",
        recipe("", "background: #{ images: \"bg\" },"),
    );
    refused(&r, &[], &["bg/a.png", special]);
    for options in ["", ", #{ texture: \"t.png\" }"] {
        let r = write(
            &inside,
            "r.rhai",
            format!(
                "dataset(#{{ samples: 1, scene: |rng| beam(#{{ length: 2.0, width: 0.2, height: 0.3 }}).material(\"rusty steel\"{options}) }})"
            ),
        );
        refused(&r, &[], &[".png", special]);
    }
    // The recipe itself.
    refused(
        &inside.join("f.rhai"),
        &[],
        &["cannot read recipe", special],
    );

    // Sources are at most 4 MiB (a module here: only comments, valid Rhai).
    let big = format!("{}\nfn one() {{ 1 }}\n", "// padding\n".repeat(400_000));
    write(&inside, "big.rhai", &big);
    let r = write(&inside, "r.rhai", recipe("import \"big\" as big;", ""));
    refused(&r, &[], &["big.rhai", "larger than 4 MiB"]);
    let r = write(&inside, "r2.rhai", format!("{big}{}", recipe("", "")));
    refused(&r, &[], &["cannot read recipe", "larger than 4 MiB"]);

    // Images are at most 256 MiB and meshes 1 GiB, refused before reading (sparse files).
    for (name, size) in [("huge.png", 256 << 20), ("huge.obj", 1 << 30)] {
        let file = std::fs::File::create(inside.join(name)).unwrap();
        file.set_len(size + 1).unwrap();
    }
    let r = write(
        &inside,
        "r.rhai",
        "dataset(#{ samples: 1, scene: |rng| beam(#{ length: 2.0, width: 0.2, height: 0.3 }).material(\"steel\", #{ texture: \"huge.png\" }) })",
    );
    refused(&r, &[], &["huge.png: is larger than 256 MiB"]);
    let r = write(
        &inside,
        "r.rhai",
        "dataset(#{ samples: 1, scene: |rng| assembly(\"a\", [shape::mesh(\"huge.obj\")]) })",
    );
    refused(&r, &[], &["huge.obj: is larger than 1 GiB"]);

    // A background folder holds at most 10000 images.
    let tiny = png(1, 1);
    for i in 0..10_001 {
        write(&inside, &format!("many/{i:05}.png"), &tiny);
    }
    let r = write(
        &inside,
        "r.rhai",
        recipe("", "background: #{ images: \"many\" },"),
    );
    refused(&r, &[], &["more than 10000 images"]);

    // Images at most 16384 pixels a side (refused from the header).
    write(&inside, "wide.png", png(20_000, 1));
    let r = write(
        &inside,
        "r.rhai",
        "dataset(#{ samples: 1, scene: |rng| beam(#{ length: 2.0, width: 0.2, height: 0.3 }).material(\"steel\", #{ texture: \"wide.png\" }) })",
    );
    refused(&r, &[], &["wide.png is 20000×1 pixels, over the limit"]);
}

#[test]
fn scripts_cannot_wait_and_their_memory_output_and_nesting_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let r = |name: &str, text: String| write(dir.path(), name, text);

    for call in [
        "sleep(1e12);",
        "sleep(100000000);",
        "Fn(\"sleep\").call(1e12);",
    ] {
        let bad = r("sleep.rhai", recipe(call, ""));
        refused(&bad, &[], &["sleep: recipes cannot wait", "sleep.rhai:1:"]);
    }

    // Rhai checks an indexed assignment's value, not the map it grows: 1500 strings of 1 MB.
    let start = Instant::now();
    let grow = r(
        "grow.rhai",
        recipe(
            "let s = \"x\"; s.pad(1000000, \"x\"); let m = #{};\nfor i in 0..1500 { m[`k${i}`] = s + i; }",
            "",
        ),
    );
    refused(
        &grow,
        &[],
        &["the script holds more than 512 MiB", "grow.rhai:2:"],
    );
    assert!(start.elapsed() < Duration::from_secs(20));

    // The same inside a scene.
    let grow = r(
        "grow2.rhai",
        "dataset(#{ samples: 3, scene: |rng| { let s = \"x\"; s.pad(1000000, \"y\"); let m = #{}; for i in 0..1500 { m[`k${i}`] = s + i; } beam(#{ length: 2.0, width: 0.2, height: 0.3 }) } })".to_string(),
    );
    refused(&grow, &[], &["the script holds more than 512 MiB"]);

    // Strings, lists and maps: the limit is named with its value.
    for (statements, limit) in [
        (
            "let s = \"x\"; s.pad(2000000, \"x\");",
            "a string would be longer than 1048576 bytes",
        ),
        (
            "let a = []; a.pad(2000000, 0);",
            "a list would hold more than 1048576 elements",
        ),
        (
            "let m = #{}; for i in 0..70000 { m[`k${i}`] = i; } m.len();",
            "a map would hold more than 65536 properties",
        ),
    ] {
        let big = r("big.rhai", recipe(statements, ""));
        refused(&big, &[], &[limit, "big.rhai:1:"]);
    }

    // Deep nesting within the limits runs on any thread (it overflowed a worker's stack).
    let nested = format!("{}f(n - 1){}", "1 + (".repeat(25), ")".repeat(25));
    let deep = r(
        "deep.rhai",
        format!(
            "fn f(n) {{ if n <= 0 {{ 0 }} else {{ {nested} }} }}\ndataset(#{{ samples: 3, camera: #{{ width: 8, height: 8 }}, scene: |rng| {{ f(62); beam(#{{ length: 2.0, width: 0.2, height: 0.3 }}) }} }})\n"
        ),
    );
    ok(run(&deep, &["--threads", "2"]));
    // Beyond them, the error names the limit.
    let endless = r(
        "endless.rhai",
        recipe("fn f(n) { [n].map(|x| f(x + 1)) }\nf(0);", ""),
    );
    let text = refused(&endless, &[], &["function calls nested more than 64 deep"]);
    assert!(
        text.contains("more calls"),
        "a long chain is shortened:\n{text}"
    );
    assert!(text.lines().count() < 30, "{text}");

    // Material prompts are at most 1000 characters: every warning quotes its prompt, so the
    // memory a prompt of unknown words takes grows with the square of its length (2600 words,
    // 15 kB, took 175 MB and 2.5 s; a 1 MB prompt would not fit in memory).
    let wordy = r(
        "wordy.rhai",
        "let p = \"\"; let a = \"abcdefghijklmnopqrstuvwxyz\";\nfor i in 0..100 { for j in 0..26 { p += `zq${a[j]}${a[i % 26]}${a[i / 26]} `; } }\ndataset(#{ samples: 1, scene: |rng| beam(#{ length: 2.0, width: 0.2, height: 0.3 }).material(p) })".to_string(),
    );
    refused(
        &wordy,
        &[],
        &[
            "material prompt \"zqaaa zqbaa",
            "is longer than 1000 characters",
            "wordy.rhai:3:",
        ],
    );

    // Profiles are at most 10000 points (checking one takes time quadratic in its points).
    let long = r(
        "profile.rhai",
        recipe(
            "let p = []; for i in 0..10001 { let t = 6.283 * i / 10001; p.push([cos(t), sin(t)]); }\nlet s = shape::extrude(p, 1.0);",
            "",
        ),
    );
    refused(
        &long,
        &[],
        &[
            "the profile has 10001 points, more than the 10000",
            "profile.rhai:2:",
        ],
    );

    // Printing is bounded: 1000 lines, each cut to 1000 characters.
    let loud = r(
        "loud.rhai",
        recipe(
            "let s = \"x\"; s.pad(10000, \"x\"); for i in 0..2000 { print(s); }",
            "",
        ),
    );
    let output = ok(run(&loud, &[]));
    let text = stderr(&output);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("recipe: x")).count(),
        1000
    );
    assert!(text.len() < 1_050_000, "{} bytes of output", text.len());
    assert!(text.contains("the rest is not shown"));
}

#[test]
fn errors_are_clear_about_encoding_closures_seeds_long_lines_and_big_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let r = |name: &str, text: &str| write(dir.path(), name, text);

    // A module that is not UTF-8 is not "not found".
    std::fs::write(
        dir.path().join("latin1.rhai"),
        b"// caf\xe9\nfn one() { 1 }\n",
    )
    .unwrap();
    let bad = r("enc.rhai", &recipe("import \"latin1\" as l;", ""));
    let text = refused(&bad, &[], &["latin1.rhai", "not UTF-8", "line 1, column 7"]);
    assert!(!text.contains("not found"), "{text}");
    let bad = dir.path().join("latin1_recipe.rhai");
    std::fs::write(&bad, b"let x = 1;\n// caf\xe9\n").unwrap();
    refused(
        &bad,
        &[],
        &["cannot read recipe", "not UTF-8", "line 2, column 7"],
    );

    // A byte-order mark starts a recipe or a module without a syntax error.
    std::fs::write(dir.path().join("bom.rhai"), b"\xef\xbb\xbffn one() { 1 }\n").unwrap();
    let with_bom = dir.path().join("with_bom.rhai");
    std::fs::write(
        &with_bom,
        format!(
            "\u{feff}{}",
            recipe("import \"bom\" as b; let one = b::one();", "")
        ),
    )
    .unwrap();
    ok(run(&with_bom, &[]));

    // A scene closure of the wrong arity is named as such, at the dataset call.
    for (closure, takes) in [("||", "0 parameters"), ("|rng, extra|", "2 parameters")] {
        let bad = r(
            "arity.rhai",
            &format!(
                "let k = 0.3;\ndataset(#{{ scene: {closure} beam(#{{ length: 2.0, width: 0.2, height: k }}) }})\n"
            ),
        );
        let text = refused(
            &bad,
            &[],
            &[&format!("dataset.scene takes {takes}"), "arity.rhai:2:1"],
        );
        assert!(!text.contains("anon$"), "{text}");
    }
    let bad = r("call.rhai", &recipe("let f = |a, b| a; f.call(1);", ""));
    let text = refused(&bad, &[], &["a closure was called with 1 argument"]);
    assert!(!text.contains("anon$"), "{text}");

    // Seeds: the whole u64 range, as strings beyond Rhai's integers; 0 stays valid.
    for (seed, recorded) in [
        ("0", 0u64),
        ("\"9223372036854775808\"", 1 << 63),
        ("\"18446744073709551615\"", u64::MAX),
        ("1e6", 1_000_000),
    ] {
        let seeded = r("seed.rhai", &recipe("", &format!("seed: {seed},")));
        ok(run(&seeded, &[]));
        let run_json = read_json(&dir.path().join("out/run.json"));
        assert_eq!(
            run_json["dataset"]["seed"].as_u64(),
            Some(recorded),
            "{seed}"
        );
    }
    let bad = r("seed.rhai", &recipe("", "seed: 9223372036854775808,"));
    refused(
        &bad,
        &[],
        &[
            "dataset.seed = 9.223372036854776e18",
            "seed: \"9223372036854775808\"",
        ],
    );
    let bad = r("seed.rhai", &recipe("", "seed: -1,"));
    refused(
        &bad,
        &[],
        &["dataset.seed = -1 must be a whole number from 0 to 18446744073709551615"],
    );
    let bad = r("seed.rhai", &recipe("", "seed: param(\"seed\", 0),"));
    refused(
        &bad,
        &["--set", "seed=9223372036854775808"],
        &[
            "expected a whole number from -9223372036854775808 to 9223372036854775807",
            "param(\"seed\", \"0\")",
        ],
    );
    for (value, expected) in [
        ("abc", "expected a whole number"),
        ("1.5", "expected a whole number"),
    ] {
        refused(
            &bad,
            &["--set", &format!("seed={value}")],
            &[expected, "default is 0"],
        );
    }

    // A long line is shown around the caret, which stays on the right character.
    let long = r(
        "long.rhai",
        &format!("let x = 1;{}x +;\n{}", " ".repeat(10_000), recipe("", "")),
    );
    let text = refused(&long, &[], &["long.rhai:1:"]);
    assert!(
        text.len() < 2_000,
        "{} bytes of output:\n{text}",
        text.len()
    );
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().position(|l| l.starts_with("1 | ")).unwrap();
    let caret = lines[at + 1].find('^').unwrap();
    let source: Vec<char> = lines[at].chars().collect();
    let under = lines[at + 1][..caret].chars().count();
    assert_eq!(
        source[under], ';',
        "caret under the wrong character:\n{text}"
    );

    // Numbers in messages are short.
    let bad = r(
        "big.rhai",
        "dataset(#{ scene: |rng| { rng.uniform(1e308, 1.0); beam(#{ length: 2.0, width: 0.2, height: 0.3 }) } })",
    );
    refused(
        &bad,
        &[],
        &["uniform(1e308, 1): the low end exceeds the high end"],
    );
    let bad = r(
        "colour.rhai",
        &recipe("", "light: #{ ambient: [1e300, 1e-300] },"),
    );
    refused(
        &bad,
        &[],
        &["[1e300, 1e-300]: the low end exceeds the high end"],
    );
}

#[test]
fn thread_and_preview_counts_are_bounded_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let r = write(dir.path(), "r.rhai", recipe("", ""));
    for threads in ["100000", "0", "many"] {
        let output = run(&r, &["--threads", threads]);
        assert!(!output.status.success());
        let text = stderr(&output);
        assert!(
            text.contains("expected a whole number of worker threads from 1 to 1024"),
            "{text}"
        );
    }
    let output = run_within(
        Duration::from_secs(60),
        &[
            "watch".as_ref(),
            r.as_os_str(),
            "--once".as_ref(),
            "--samples".as_ref(),
            "1000000".as_ref(),
        ],
    );
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("1000000 is not in 1..=100"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn magnitudes_beyond_any_structure_are_refused_at_the_recipe_line() {
    let dir = tempfile::tempdir().unwrap();
    let with_scene = |name: &str, scene: &str| {
        let text = recipe("", "").replace(SCENE, &format!("scene: |rng| {scene}"));
        write(dir.path(), name, &text)
    };
    // Far from the origin, f64 positions quantise the structure: refused, not rendered.
    let far = with_scene(
        "far.rhai",
        "beam(#{ length: 2.0, width: 0.2, height: 0.3 }).at(1e15, 0.0, 0.0)",
    );
    refused(
        &far,
        &[],
        &[
            "far.rhai:2:",
            "1e7 m any scene coordinate may reach",
            "1e15",
        ],
    );
    // A shell pattern reaching the axis is a collapse, not a damage state; two patterns that
    // are each fine may not sum past the limit.
    let collapse = with_scene(
        "collapse.rhai",
        "assembly(\"s\", [shape::tube(1.0, 3.0, 0.05).elephant_foot(1e20, 0.5)])",
    );
    refused(
        &collapse,
        &[],
        &["collapse.rhai:2:", "elephant_foot", "at most 0.5 m"],
    );
    let summed = with_scene(
        "summed.rhai",
        "assembly(\"s\", [shape::tube(1.0, 3.0, 0.05).hoop_expansion(0.3).ovalise(0.3, 2, 0.0)])",
    );
    refused(&summed, &[], &["summed.rhai:2:", "reach 0.6 m together"]);
    // Just inside the limits renders.
    let inside = with_scene(
        "inside.rhai",
        "assembly(\"s\", [shape::tube(1.0, 3.0, 0.05).hoop_expansion(0.2).ovalise(0.3, 2, 0.0).translate(9e6, 0.0, 0.0)])",
    );
    ok(run(&inside, &[]));
}
