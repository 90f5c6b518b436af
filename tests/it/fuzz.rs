//! Property-based fuzzing of everything that reads files: scene JSON,
//! `.trs` scenes, OBJ/MTL meshes, scene cache entries, and the EXR and
//! PFM-with-sidecar images `tracer merge` reads. Inputs are arbitrary bytes
//! and structured mutations of valid files (values replaced by extremes
//! such as 1e308, -0, 2^64 - 1 or 1e999, keys added and removed, deep
//! nesting, sizes and indices in the billions). Every input must give a
//! value or a clean error: no panic, and an answer within [`BUDGET`] (a
//! hang, or an allocation sized by a number in the input, blows it). What
//! is accepted must also be usable: settings that pass their own check, a
//! mesh whose indices are in range, a cache entry whose BVH can be traced.
//!
//! Each property runs [`DEFAULT_CASES`] cases in `cargo test`;
//! `TRACER_FUZZ_CASES=N` runs N instead. The generator's seed is fixed, so
//! CI runs the same cases every time; `TRACER_FUZZ_SEED=N` (or `random`)
//! explores others. A failure prints the shrunk input.

use crate::common::{self, write};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::time::Duration;
use tempfile::TempDir;

/// Cases per property unless `TRACER_FUZZ_CASES` says otherwise.
const DEFAULT_CASES: u32 = 256;

/// The longest one case may take. Generous, because other tests share
/// the cores: a reader looping forever or allocating gigabytes because a
/// header asked for them takes far longer (or aborts the process).
const BUDGET: Duration = Duration::from_secs(5);

fn config() -> Config {
    let cases = std::env::var("TRACER_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(DEFAULT_CASES);
    let rng_seed = match std::env::var("TRACER_FUZZ_SEED").as_deref() {
        Ok("random") => RngSeed::Random,
        Ok(n) => RngSeed::Fixed(n.parse().expect("TRACER_FUZZ_SEED: a number or `random`")),
        Err(_) => RngSeed::Fixed(0x7ace_5eed),
    };
    Config {
        rng_seed,
        // Failures are reported with their shrunk input, not saved as
        // files in the source tree.
        failure_persistence: None,
        max_shrink_time: 60_000,
        ..Config::with_cases(cases)
    }
}

/// Runs `property` on `cases` values of `strategy`; panics with the shrunk
/// failing input if any fails.
/// Runs `property` on the configured number of values of `strategy`;
/// panics with the shrunk failing input if any fails. The property says
/// whether the reader accepted its input; how many it accepted is printed
/// (seen with `--nocapture`), to show the cases reach past the first check.
fn check<S: Strategy>(
    what: &str,
    strategy: S,
    property: impl Fn(S::Value) -> Result<bool, TestCaseError>,
) where
    S::Value: std::fmt::Debug,
{
    use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
    let (cases, accepted) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let mut runner = TestRunner::new(config());
    let result = runner.run(&strategy, |value| {
        let ok = property(value)?;
        cases.fetch_add(1, Relaxed);
        accepted.fetch_add(ok as usize, Relaxed);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    eprintln!(
        "{what}: {} of {} inputs accepted",
        accepted.load(Relaxed),
        cases.load(Relaxed)
    );
}

/// Runs `f` on a thread of its own and returns its value, failing the case
/// if it panics or takes longer than [`BUDGET`].
fn within<T: Send + 'static>(
    what: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, TestCaseError> {
    let (done, finished) = channel();
    let worker = std::thread::spawn(move || {
        let value = f();
        let _ = done.send(());
        value
    });
    match finished.recv_timeout(BUDGET) {
        Ok(()) | Err(RecvTimeoutError::Disconnected) => worker.join().map_err(|panic| {
            let message = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            TestCaseError::fail(format!("{what} panicked: {message}"))
        }),
        // The worker is left to run: it cannot be stopped from here.
        Err(RecvTimeoutError::Timeout) => Err(TestCaseError::fail(format!(
            "{what} took longer than {BUDGET:?}"
        ))),
    }
}

// ---------------------------------------------------------------------------
// Mutations of JSON documents, shared by scenes, .trs files and sidecars.

/// A value to put somewhere in a document.
#[derive(Clone, Debug)]
enum Extreme {
    Float(f64),
    Int(i64),
    UInt(u64),
    /// Number text serde_json would not write: `1e999`, 400 digits, `-0`.
    Raw(String),
    Null,
    Bool(bool),
    Str(String),
    EmptyArray,
    EmptyObject,
    /// The value nested in this many arrays.
    Nested(usize),
    /// An array of many copies of a small value.
    Long(usize),
    /// An ordinary value: most edits should leave a file that loads.
    Plain(Value),
}

fn extreme() -> impl Strategy<Value = Extreme> {
    let floats = prop_oneof![
        Just(1e308),
        Just(-1e308),
        Just(-0.0),
        Just(0.0),
        Just(5e-324),
        Just(f64::MIN_POSITIVE),
        Just(3.4028235e38),
        Just(3.5e38),
        Just(-3.5e38),
        Just(1e-46),
        Just(179.99999),
        Just(180.0),
        Just(0.5),
        Just(-1.0),
        any::<f64>().prop_filter("finite", |x| x.is_finite()),
    ];
    let ints = prop_oneof![
        Just(0i64),
        Just(-1),
        Just(1),
        Just(3),
        Just(10),
        Just(11),
        Just(65536),
        Just(i32::MAX as i64),
        Just(u32::MAX as i64),
        Just(u32::MAX as i64 + 1),
        Just(i64::MIN),
        Just(i64::MAX),
        any::<i64>(),
    ];
    let raws = prop_oneof![
        Just("1e999".to_string()),
        Just("-1e999".to_string()),
        Just("1e-999".to_string()),
        Just("-0".to_string()),
        Just("0.0000000000000000000000000000000000000000000001".to_string()),
        Just("9".repeat(400)),
        Just(format!("-{}", "9".repeat(30))),
        Just("18446744073709551616".to_string()),
    ];
    let strings = prop_oneof![
        Just(String::new()),
        Just(" ".to_string()),
        Just("\u{feff}".to_string()),
        Just("x".repeat(5000)),
        Just("/dev/zero".to_string()),
        Just("../../../../etc/hostname".to_string()),
        Just("mesh.obj".to_string()),
        Just("texture.png".to_string()),
        Just("Triangle.obj".to_string()),
        Just("out.png".to_string()),
        Just("out.bmp".to_string()),
        Just("white".to_string()),
        Just("default".to_string()),
        prop::sample::select(TYPE_NAMES).prop_map(str::to_string),
        "[ -~]{0,12}",
        ".{0,8}",
    ];
    let plain = prop_oneof![
        (-10.0f64..10.0).prop_map(|x| json!(x)),
        (0i64..16).prop_map(|x| json!(x)),
        [0.0f64..2.0, 0.0f64..2.0, 0.0f64..2.0].prop_map(|c| json!(c)),
        [-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0].prop_map(|c| json!(c)),
    ];
    prop_oneof![
        12 => plain.prop_map(Extreme::Plain),
        1 => floats.prop_map(Extreme::Float),
        1 => ints.prop_map(Extreme::Int),
        1 => any::<u64>().prop_map(Extreme::UInt),
        1 => Just(Extreme::UInt(u64::MAX)),
        1 => raws.prop_map(Extreme::Raw),
        1 => Just(Extreme::Null),
        1 => any::<bool>().prop_map(Extreme::Bool),
        1 => strings.prop_map(Extreme::Str),
        1 => Just(Extreme::EmptyArray),
        1 => Just(Extreme::EmptyObject),
        1 => prop_oneof![Just(129usize), Just(200), 1usize..8].prop_map(Extreme::Nested),
        1 => prop_oneof![Just(3usize), Just(4), Just(16), Just(3000)].prop_map(Extreme::Long),
    ]
}

/// The type names and keys of both scene formats, so that random edits
/// reach past the first check.
const TYPE_NAMES: &[&str] = &[
    "mesh",
    "quad",
    "cube",
    "sphere",
    "triangles",
    "diffuse",
    "mirror",
    "dielectric",
    "point",
    "spot",
    "directional",
    "pt",
    "lt",
    "bdpt",
    "srgb",
    "aces",
    "gamma",
    "clamp",
    "Camera",
    "Light",
    "Mesh",
    "Point",
    "Area",
    "PFM",
    "TGA",
    "Window",
    "Diffuse",
    "Mirror",
    "Glass",
];
const KEYS: &[&str] = &[
    "format",
    "name",
    "camera",
    "film",
    "render",
    "materials",
    "objects",
    "lights",
    "position",
    "look_at",
    "up",
    "fov",
    "width",
    "height",
    "output",
    "tonemap",
    "exposure",
    "integrator",
    "spp",
    "max_depth",
    "seed",
    "time_limit",
    "type",
    "file",
    "material",
    "transform",
    "emission",
    "two_sided",
    "matrix",
    "scale",
    "rotate",
    "translate",
    "center",
    "radius",
    "subdivisions",
    "positions",
    "indices",
    "normals",
    "uvs",
    "albedo",
    "texture",
    "ior",
    "reflectance",
    "transmittance",
    "intensity",
    "cone_angle",
    "falloff_start",
    "direction",
    "irradiance",
    "Type",
    "Position",
    "ResX",
    "ResY",
    "LightType",
    "Intensity",
    "Vertices",
    "MeshName",
    "Mesh Material",
    "SceneName",
    "Display",
    "Name",
    "Colour",
    "Texture",
    "NumberOfVertices",
    "spp",
    "crop",
    "samples",
    "pixelsHash",
    "pixels_hash",
    "stopped_by",
];

/// One edit at a node chosen among all the document's nodes.
#[derive(Clone, Debug)]
enum Edit {
    Replace(Index, Extreme),
    Remove(Index),
    Insert(Index, String, Extreme),
    /// Copies one node over another (a sphere's keys into a light, say).
    Copy(Index, Index),
}

fn edit() -> impl Strategy<Value = Edit> {
    let key = prop_oneof![
        4 => prop::sample::select(KEYS).prop_map(str::to_string),
        1 => "[a-z_]{1,8}",
    ];
    prop_oneof![
        6 => (any::<Index>(), extreme()).prop_map(|(i, x)| Edit::Replace(i, x)),
        2 => any::<Index>().prop_map(Edit::Remove),
        2 => (any::<Index>(), key, extreme()).prop_map(|(i, k, x)| Edit::Insert(i, k, x)),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Edit::Copy(a, b)),
    ]
}

/// A step from a node to a child.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    At(usize),
}

/// The path to every node, the root first.
fn node_paths(v: &Value) -> Vec<Vec<Step>> {
    fn walk(v: &Value, path: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
        out.push(path.clone());
        match v {
            Value::Object(m) => {
                for (k, child) in m {
                    path.push(Step::Key(k.clone()));
                    walk(child, path, out);
                    path.pop();
                }
            }
            Value::Array(a) => {
                for (i, child) in a.iter().enumerate() {
                    path.push(Step::At(i));
                    walk(child, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(v, &mut Vec::new(), &mut out);
    out
}

fn node_mut<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, step| match step {
        Step::Key(k) => &mut v[k.as_str()],
        Step::At(i) => &mut v[*i],
    })
}

/// Applies `edits` to `doc` and returns its text; `Raw` numbers are put
/// in as text after serialising.
fn apply(mut doc: Value, edits: &[Edit]) -> String {
    let mut raws = Vec::new();
    let mut value_of = |x: &Extreme| -> Value {
        match x {
            Extreme::Float(f) => json!(f),
            Extreme::Int(i) => json!(i),
            Extreme::UInt(u) => json!(u),
            Extreme::Raw(text) => {
                raws.push(text.clone());
                json!(format!("@@raw{}@@", raws.len() - 1))
            }
            Extreme::Null => Value::Null,
            Extreme::Bool(b) => json!(b),
            Extreme::Str(s) => json!(s),
            Extreme::EmptyArray => json!([]),
            Extreme::EmptyObject => json!({}),
            Extreme::Nested(depth) => (0..*depth).fold(json!(1), |v, _| json!([v])),
            Extreme::Long(n) => Value::Array(vec![json!([0.5, 0.25, 1]); *n]),
            Extreme::Plain(v) => v.clone(),
        }
    };
    for e in edits {
        let paths = node_paths(&doc);
        match e {
            Edit::Replace(at, x) => {
                let value = value_of(x);
                *node_mut(&mut doc, &paths[at.index(paths.len())]) = value;
            }
            Edit::Remove(at) => {
                let path = &paths[at.index(paths.len())];
                if let Some((last, parent)) = path.split_last() {
                    match (node_mut(&mut doc, parent), last) {
                        (Value::Object(m), Step::Key(k)) => {
                            m.remove(k);
                        }
                        (Value::Array(a), Step::At(i)) => {
                            a.remove(*i);
                        }
                        _ => {}
                    }
                }
            }
            Edit::Insert(at, key, x) => {
                let value = value_of(x);
                match node_mut(&mut doc, &paths[at.index(paths.len())]) {
                    Value::Object(m) => {
                        m.insert(key.clone(), value);
                    }
                    Value::Array(a) => a.push(value),
                    other => *other = value,
                }
            }
            Edit::Copy(from, to) => {
                let value = node_mut(&mut doc, &paths[from.index(paths.len())]).clone();
                *node_mut(&mut doc, &paths[to.index(paths.len())]) = value;
            }
        }
    }
    let mut text = serde_json::to_string_pretty(&doc).unwrap();
    for (k, raw) in raws.iter().enumerate() {
        text = text.replace(&format!("\"@@raw{k}@@\""), raw);
    }
    text
}

/// Edits to bytes of a file.
#[derive(Clone, Debug)]
enum ByteEdit {
    Flip(Index, u8),
    Set(Index, u8),
    Insert(Index, Vec<u8>),
    Delete(Index, usize),
    Truncate(Index),
    Extend(Vec<u8>),
}

fn byte_edit() -> impl Strategy<Value = ByteEdit> {
    prop_oneof![
        4 => (any::<Index>(), 0u8..8).prop_map(|(i, b)| ByteEdit::Flip(i, 1 << b)),
        3 => (any::<Index>(), any::<u8>()).prop_map(|(i, b)| ByteEdit::Set(i, b)),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(i, b)| ByteEdit::Insert(i, b)),
        1 => (any::<Index>(), 1usize..64).prop_map(|(i, n)| ByteEdit::Delete(i, n)),
        1 => any::<Index>().prop_map(ByteEdit::Truncate),
        1 => prop::collection::vec(any::<u8>(), 1..128).prop_map(ByteEdit::Extend),
    ]
}

fn apply_bytes(bytes: &mut Vec<u8>, edits: &[ByteEdit]) {
    for e in edits {
        let n = bytes.len();
        match e {
            ByteEdit::Flip(i, bit) if n > 0 => bytes[i.index(n)] ^= bit,
            ByteEdit::Set(i, b) if n > 0 => bytes[i.index(n)] = *b,
            ByteEdit::Insert(i, b) => {
                let at = i.index(n + 1);
                bytes.splice(at..at, b.iter().copied());
            }
            ByteEdit::Delete(i, k) if n > 0 => {
                let at = i.index(n);
                bytes.drain(at..(at + k).min(n));
            }
            ByteEdit::Truncate(i) => bytes.truncate(i.index(n + 1)),
            ByteEdit::Extend(b) => bytes.extend_from_slice(b),
            _ => {}
        }
    }
}

/// Arbitrary bytes, JSON-like token soup, or edits of `valid`'s bytes.
fn text_inputs(valid: String) -> impl Strategy<Value = Vec<u8>> {
    let tokens = prop::collection::vec(
        prop_oneof![
            prop::sample::select(
                &[
                    "{",
                    "}",
                    "[",
                    "]",
                    ":",
                    ",",
                    "\"",
                    "null",
                    "true",
                    "1e999",
                    "-0",
                    "1e308",
                    "18446744073709551616",
                    "0",
                    "\\u0000",
                    "\\ud800",
                    "\u{feff}",
                    " ",
                ][..]
            )
            .prop_map(str::to_string),
            prop::sample::select(KEYS).prop_map(|k| format!("\"{k}\"")),
            prop::sample::select(TYPE_NAMES).prop_map(|k| format!("\"{k}\"")),
        ],
        0..64,
    )
    .prop_map(|t| t.concat().into_bytes());
    let edited = prop::collection::vec(byte_edit(), 1..6).prop_map(move |edits| {
        let mut bytes = valid.clone().into_bytes();
        apply_bytes(&mut bytes, &edits);
        bytes
    });
    prop_oneof![prop::collection::vec(any::<u8>(), 0..512), tokens, edited,]
}

// ---------------------------------------------------------------------------
// (a) Scene JSON.

/// A tiny OBJ with an MTL (emissive, textured, mirror and glass materials)
/// and a 2 × 2 texture, for the scenes and meshes that name them.
fn scene_files(dir: &Path) {
    write(
        &dir.join("mesh.obj"),
        "mtllib mesh.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
         usemtl tex\nf 1/1/1 2/2/1 3/3/1\nusemtl glow\nf 1 3 4\nusemtl glass\nf 1 2 4\n",
    );
    write(
        &dir.join("mesh.mtl"),
        "newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd texture.png\nnewmtl glow\nKe 1 1 1\n\
         newmtl glass\nNi 1.5\nd 0.5\nnewmtl chrome\nillum 3\nKs 0.9 0.9 0.9\n",
    );
    let mut image = tracer::film::Image::new(2, 2);
    image.pixels[1] = glam::Vec3::ONE;
    tracer::film::write::write_image(
        &dir.join("texture.png"),
        &image,
        tracer::film::tonemap::Tonemap::Clamp,
        0.0,
    )
    .unwrap();
    std::fs::copy(dir.join("mesh.obj"), dir.join("Triangle.obj")).unwrap();
    std::fs::copy(dir.join("mesh.mtl"), dir.join("Triangle.mtl")).unwrap();
}

/// A valid scene using every section, object, material and light type.
fn rich_scene() -> Value {
    json!({
        "format": 1,
        "name": "fuzz",
        "camera": { "position": [0, 1, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40 },
        "film": { "width": 8, "height": 6, "output": "out.png", "tonemap": "aces", "exposure": 0.5 },
        "render": { "integrator": "bdpt", "spp": 2, "max_depth": 5, "seed": 3, "time_limit": 10 },
        "materials": {
            "white": { "type": "diffuse", "albedo": [0.8, 0.8, 0.8] },
            "textured": { "type": "diffuse", "albedo": { "texture": "texture.png" } },
            "chrome": { "type": "mirror", "reflectance": [0.9, 0.9, 0.9] },
            "glass": { "type": "dielectric", "ior": 1.5, "transmittance": [1, 1, 1] }
        },
        "objects": [
            { "type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 1, "material": "glass" },
            { "type": "quad", "material": "white", "transform": { "scale": 4, "translate": [0, -1, 0] } },
            { "type": "cube", "material": "chrome", "transform": { "rotate": [0, 1, 0, 30], "scale": [1, 2, 1] } },
            { "type": "triangles", "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]],
              "indices": [0, 1, 2, 1, 3, 2], "normals": [[0, 0, 1], [0, 0, 1], [0, 0, 1], [0, 0, 1]],
              "uvs": [[0, 0], [1, 0], [0, 1], [1, 1]], "material": "textured", "two_sided": true },
            { "type": "mesh", "file": "mesh.obj",
              "transform": { "matrix": [1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1, 0, 0, 0, 0, 1] } },
            { "type": "quad", "emission": [4, 4, 4], "transform": { "translate": [0, 3, 0] } }
        ],
        "lights": [
            { "type": "point", "position": [0, 2, 0], "intensity": [5, 5, 5] },
            { "type": "spot", "position": [1, 2, 0], "look_at": [0, 0, 0], "intensity": [5, 5, 5],
              "cone_angle": 40, "falloff_start": 20 },
            { "type": "directional", "direction": [0, -1, 0.2], "irradiance": [1, 1, 1] }
        ]
    })
}

/// What any accepted description must satisfy: its settings pass their
/// own check, its estimate can be taken, and a small one builds (or fails
/// cleanly) without a panic.
fn accepted_description_is_usable(desc: &tracer::format::SceneDesc) -> Result<bool, TestCaseError> {
    if let Err(e) = desc.settings.check() {
        return Err(TestCaseError::fail(format!(
            "accepted settings that fail their check: {}",
            e.message
        )));
    }
    let estimate = tracer::scene::estimate::estimate(desc, &desc.settings);
    if estimate.triangles <= 50_000 {
        let _ = tracer::scene::build(desc, None);
    }
    Ok(true)
}

#[derive(Clone, Debug)]
enum SceneInput {
    Bytes(Vec<u8>),
    Edits(Vec<Edit>),
}

fn scene_inputs(valid: Value) -> impl Strategy<Value = SceneInput> {
    let text = serde_json::to_string_pretty(&valid).unwrap();
    prop_oneof![
        1 => text_inputs(text).prop_map(SceneInput::Bytes),
        4 => prop::collection::vec(edit(), 1..4).prop_map(SceneInput::Edits),
    ]
}

fn scene_text(input: &SceneInput, valid: &Value) -> String {
    match input {
        SceneInput::Bytes(b) => String::from_utf8_lossy(b).into_owned(),
        SceneInput::Edits(e) => apply(valid.clone(), e),
    }
}

#[test]
fn scene_json_gives_a_scene_or_an_error() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    scene_files(dir.path());
    let file = dir.path().join("scene.json");
    let valid = rich_scene();
    // The starting point is itself valid.
    let desc = tracer::format::json::parse(&apply(valid.clone(), &[]), &file).unwrap();
    tracer::scene::build(&desc, None).unwrap();
    check("scene JSON", scene_inputs(valid.clone()), |input| {
        let text = scene_text(&input, &valid);
        let file = file.clone();
        within("json::parse", move || {
            match tracer::format::json::parse(&text, &file) {
                Ok(desc) => accepted_description_is_usable(&desc),
                // Errors echo bits of the input: never much of it.
                Err(e) => {
                    let message = e.to_string();
                    prop_assert!(message.len() <= 4096, "an error of {} bytes", message.len());
                    Ok(false)
                }
            }
        })?
    });
}

// ---------------------------------------------------------------------------
// (b) T-racer .trs scenes.

fn rich_trs() -> Value {
    json!({
        "SceneName": "Fuzz",
        "Display": { "Name": "Out", "Type": "PFM", "ResX": 8, "ResY": 6 },
        "Camera": { "Type": "Camera", "Name": "Cam", "Position": [0.0, 1.0, -3.0], "fov": 60.0 },
        "Lamp": { "Type": "Light", "LightType": "Point", "Position": [0.0, 2.0, 0.0], "Intensity": [4.0, 4.0, 4.0] },
        "Panel": {
            "Type": "Light", "LightType": "Area", "Intensity": [2.0, 2.0, 2.0], "NumberOfVertices": 3,
            "Vertices": [[-1.0, 2.9, -1.0], [1.0, 2.9, -1.0], [0.0, 2.9, 1.0]]
        },
        "Floor": { "Type": "Mesh", "MeshName": "mesh.obj", "Mesh Material": "Diffuse", "Colour": [1, 1, 1] },
        "Ball": { "Type": "Mesh", "MeshName": "Triangle.obj", "Mesh Material": "Glass", "Texture": "" }
    })
}

#[test]
fn trs_scenes_give_a_scene_or_an_error() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    scene_files(dir.path());
    let file = dir.path().join("scene.trs");
    let valid = rich_trs();
    let desc = tracer::format::trs::parse(&apply(valid.clone(), &[]), &file).unwrap();
    tracer::scene::build(&desc, None).unwrap();
    check(".trs", scene_inputs(valid.clone()), |input| {
        let text = scene_text(&input, &valid);
        let file = file.clone();
        within("trs::parse", move || {
            match tracer::format::trs::parse(&text, &file) {
                Ok(desc) => accepted_description_is_usable(&desc),
                Err(_) => Ok(false),
            }
        })?
    });
}

// ---------------------------------------------------------------------------
// (c) OBJ and MTL files.

fn number_token() -> impl Strategy<Value = String> {
    prop_oneof![
        40 => (-4.0f32..4.0).prop_map(|x| x.to_string()),
        1 => prop::sample::select(&[
            "0", "-0", "1e39", "-1e39", "1e-50", "nan", "NaN", "inf", "-inf", "1e308",
            "3.4028235e38", "", "1.2.3", "0x10", "--1", "1e",
        ][..])
        .prop_map(str::to_string),
    ]
}

fn index_token() -> impl Strategy<Value = String> {
    let index = prop_oneof![
        30 => (1i64..=8).prop_map(|i| i.to_string()),
        6 => (-8i64..=-1).prop_map(|i| i.to_string()),
        1 => prop::sample::select(&[
            "0", "4000000000", "2147483648", "4294967296", "-4000000000",
            "9223372036854775807", "-9223372036854775808", "18446744073709551615", "x", "",
        ][..])
        .prop_map(str::to_string),
    ];
    let slashes = prop::sample::select(&["{v}", "{v}/{t}", "{v}//{n}", "{v}/{t}/{n}", "{v}/"][..]);
    (index.clone(), index.clone(), index, slashes).prop_map(|(v, t, n, shape)| {
        shape
            .replace("{v}", &v)
            .replace("{t}", &t)
            .replace("{n}", &n)
    })
}

fn obj_line() -> impl Strategy<Value = String> {
    let nums = |k: usize| prop::collection::vec(number_token(), k).prop_map(|v| v.join(" "));
    prop_oneof![
        8 => nums(3).prop_map(|n| format!("v {n}")),
        1 => nums(4).prop_map(|n| format!("v {n}")),
        2 => nums(2).prop_map(|n| format!("vt {n}")),
        2 => nums(3).prop_map(|n| format!("vn {n}")),
        16 => prop::collection::vec(index_token(), 1..9).prop_map(|f| format!("f {}", f.join(" "))),
        1 => prop::sample::select(&["tex", "glow", "glass", "chrome", "nowhere", ""][..])
            .prop_map(|m| format!("usemtl {m}")),
        1 => prop::sample::select(&["fuzz.mtl", "missing.mtl", "/dev/zero", "fuzz.mtl extra.mtl", ""][..])
            .prop_map(|m| format!("mtllib {m}")),
        1 => prop::sample::select(&["o thing", "g group", "s 1", "s off", "# comment", "l 1 2", "p 1", ""][..])
            .prop_map(str::to_string),
        1 => "[ -~]{0,24}",
    ]
}

fn mtl_line() -> impl Strategy<Value = String> {
    let nums = |k: usize| prop::collection::vec(number_token(), k).prop_map(|v| v.join(" "));
    prop_oneof![
        3 => prop::sample::select(&["tex", "glow", "glass", "chrome", ""][..])
            .prop_map(|m| format!("newmtl {m}")),
        2 => (prop::sample::select(&["Kd", "Ke", "Ks", "Ka"][..]), nums(3))
            .prop_map(|(k, n)| format!("{k} {n}")),
        2 => (prop::sample::select(&["Ni", "d", "Tr", "Ns"][..]), number_token())
            .prop_map(|(k, n)| format!("{k} {n}")),
        1 => prop::sample::select(&["0", "2", "3", "5", "7", "4000000000", "-1", "x"][..])
            .prop_map(|i| format!("illum {i}")),
        1 => prop::sample::select(&["texture.png", "missing.png", "/dev/zero", "mesh.obj", ""][..])
            .prop_map(|t| format!("map_Kd {t}")),
        1 => "[ -~]{0,24}",
    ]
}

/// What every generated OBJ starts with: its MTL, and eight positions,
/// texture coordinates and normals, so that most faces name vertices that
/// exist.
const OBJ_PREFIX: &str = "mtllib fuzz.mtl
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0\nvt 0 0.5\nvt 0.5 0.5\nvt 1 0.5
vn 0 0 1\nvn 0 1 0\nvn 1 0 0\nvn 0 0 -1\nvn 0 -1 0\nvn -1 0 0\nvn 0.6 0.8 0\nvn 0 0.6 0.8";

#[derive(Clone, Debug)]
enum ObjInput {
    Lines { obj: Vec<String>, mtl: Vec<String> },
    Bytes { obj: Vec<u8>, mtl: Vec<u8> },
}

fn obj_inputs() -> impl Strategy<Value = (ObjInput, u8)> {
    let input = prop_oneof![
        4 => (
            prop::collection::vec(obj_line(), 0..40),
            prop::collection::vec(mtl_line(), 0..16),
        )
            .prop_map(|(obj, mtl)| ObjInput::Lines { obj, mtl }),
        1 => (
            prop::collection::vec(any::<u8>(), 0..1024),
            prop::collection::vec(any::<u8>(), 0..256),
        )
            .prop_map(|(obj, mtl)| ObjInput::Bytes { obj, mtl }),
    ];
    (input, 0u8..4)
}

#[test]
fn obj_and_mtl_files_give_a_mesh_or_an_error() {
    use tracer::format::desc::MaterialOverride;
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    scene_files(dir.path());
    let obj = dir.path().join("fuzz.obj");
    let mtl = dir.path().join("fuzz.mtl");
    // A scene around the mesh, so that what loads is also built.
    let mut scene = rich_scene();
    scene["objects"] = json!([{ "type": "mesh", "file": "fuzz.obj" }]);
    let scene = common::write_json(dir.path(), "fuzz.json", &scene);
    check(
        "OBJ/MTL (with triangles)",
        obj_inputs(),
        |(input, choice)| {
            let (obj_bytes, mtl_bytes) = match input {
                ObjInput::Lines { obj, mtl } => (
                    [OBJ_PREFIX, &obj.join("\n")].join("\n").into_bytes(),
                    mtl.join("\n").into_bytes(),
                ),
                ObjInput::Bytes { obj, mtl } => (obj, mtl),
            };
            std::fs::write(&obj, obj_bytes).unwrap();
            std::fs::write(&mtl, mtl_bytes).unwrap();
            let mtl_override = [
                None,
                Some(MaterialOverride::Diffuse),
                Some(MaterialOverride::Mirror),
                Some(MaterialOverride::Glass),
            ][choice as usize];
            let (obj, scene) = (obj.clone(), scene.clone());
            within("load_obj", move || -> Result<bool, TestCaseError> {
                let mut triangles = 0;
                if let Ok(file) = tracer::format::obj::load_obj(&obj, mtl_override) {
                    for group in &file.groups {
                        triangles += group.mesh.indices.len() / 3;
                        let mesh = &group.mesh;
                        let n = mesh.positions.len();
                        prop_assert!(mesh.indices.iter().all(|&i| (i as usize) < n));
                        prop_assert!(mesh.normals.as_ref().is_none_or(|v| v.len() == n));
                        prop_assert!(mesh.uvs.as_ref().is_none_or(|v| v.len() == n));
                    }
                }
                let desc = tracer::format::read_scene(&scene).unwrap();
                let _ = tracer::scene::build(&desc, None);
                Ok(triangles > 0)
            })?
        },
    );
}

// ---------------------------------------------------------------------------
// (d) Scene cache entries.

#[derive(Clone, Debug)]
struct EntryInput {
    edits: Vec<ByteEdit>,
    /// Rewrites the payload length and checksum after the edits, so that
    /// they reach the checks behind the checksum.
    reseal: bool,
}

/// Makes the header's payload length and checksum agree with `bytes`.
fn reseal(bytes: &mut [u8]) {
    use tracer::scene::cache::entry::HEADER_BYTES;
    if bytes.len() < HEADER_BYTES {
        return;
    }
    let count = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let table_end = HEADER_BYTES + count.min(1 << 20) * 16;
    let payload = bytes.len().saturating_sub(table_end) as u64;
    bytes[48..56].copy_from_slice(&payload.to_le_bytes());
    let checksum = *blake3::hash(&bytes[HEADER_BYTES..]).as_bytes();
    bytes[56..88].copy_from_slice(&checksum);
}

#[test]
fn damaged_cache_entries_are_refused_or_sound() {
    use tracer::bvh::BuildOptions;
    use tracer::scene::cache::{scene_key, Cache, CacheUse};
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    scene_files(dir.path());
    let mut scene = rich_scene();
    // Small, so each case is quick: 80 sphere triangles, the quads, the
    // cube, the inline triangles and the OBJ's three (one emissive).
    scene["render"] = json!({ "spp": 1, "max_depth": 3 });
    scene["film"] = json!({ "width": 4, "height": 4 });
    let path = common::write_json(dir.path(), "cached.json", &scene);
    let desc = tracer::format::read_scene(&path).unwrap();
    let cache = Cache::new(dir.path().join("cache")).with_min_triangles(0);
    let stored = tracer::scene::build(&desc, Some(&cache)).unwrap();
    assert_eq!(stored.report.cache, CacheUse::Stored);
    let key = scene_key(&desc, &BuildOptions::default()).unwrap();
    let entry = cache.entry_path(&key);
    let pristine = std::fs::read(&entry).unwrap();
    // The scene's own materials and the built-in default come before the
    // entry's MTL materials.
    let scene_materials = desc.materials.len() + 1;
    assert!(cache
        .lookup(&key, scene_materials, &mut Vec::new())
        .is_some());
    let shared = std::sync::Arc::new((cache, desc, entry, pristine));

    let inputs = (prop::collection::vec(byte_edit(), 1..5), any::<bool>())
        .prop_map(|(edits, reseal)| EntryInput { edits, reseal });
    check("cache entries", inputs, |input| {
        let shared = shared.clone();
        within("cache lookup", move || -> Result<bool, TestCaseError> {
            let (cache, desc, entry, pristine) = &*shared;
            let mut bytes = pristine.clone();
            apply_bytes(&mut bytes, &input.edits);
            if input.reseal {
                reseal(&mut bytes);
            }
            // A new file renamed into place, as the cache writes them: a
            // mapping of an earlier case's file is never truncated.
            let temp = entry.with_extension("fuzz");
            std::fs::write(&temp, &bytes).unwrap();
            std::fs::rename(&temp, entry).unwrap();
            let key = scene_key(desc, &tracer::bvh::BuildOptions::default()).unwrap();
            let mut warnings = Vec::new();
            let found = cache.lookup(&key, scene_materials, &mut warnings);
            if found.is_none() {
                return Ok(false);
            }
            drop(found);
            // Without a reseal, any change at all must be caught.
            prop_assert!(
                input.reseal || bytes == *pristine,
                "a damaged entry was trusted"
            );
            // Accepted: it must be usable. Build the scene from it, trace
            // rays through its BVH and render a few pixels.
            let scene = tracer::scene::build(desc, Some(cache)).unwrap();
            let mut rng = common::Rng::new(bytes.len() as u64);
            for _ in 0..256 {
                let ray = tracer::geometry::Ray::new(rng.vec3(-6.0, 6.0), rng.unit_vector());
                if let Some(hit) = scene.intersect(&ray) {
                    prop_assert!((hit.triangle as usize) < scene.triangles.len());
                    let _ = scene.surface(&hit);
                }
                let _ = scene.occluded(&ray);
            }
            let options = tracer::render::RenderOptions {
                threads: Some(1),
                progress: false,
                ..Default::default()
            };
            let _ = tracer::render::render(&scene, &desc.settings, &options);
            Ok(true)
        })?
    });
}

// ---------------------------------------------------------------------------
// (e) What `tracer merge` reads: EXR with attributes, PFM with a sidecar.

fn merge_part(dir: &Path, name: &str) -> PathBuf {
    let mut image = tracer::film::Image::new(6, 4);
    for (k, p) in image.pixels.iter_mut().enumerate() {
        *p = glam::Vec3::new(k as f32 * 0.1, 0.5, 2.0);
    }
    let metadata = tracer::film::metadata::Metadata {
        passes: 3,
        noise: Some(0.1),
        ..common::metadata(6, 4, 4)
    };
    let path = dir.join(name);
    tracer::film::write::write_image_with(
        &path,
        &image,
        tracer::film::tonemap::Tonemap::Clamp,
        0.0,
        Some(&metadata),
    )
    .unwrap();
    path
}

/// What an accepted image must satisfy.
fn read_image_is_sound(
    read: &tracer::Result<(tracer::film::Image, tracer::film::metadata::Metadata)>,
) -> Result<bool, TestCaseError> {
    if let Ok((image, _)) = read {
        prop_assert_eq!(
            image.pixels.len(),
            image.width as usize * image.height as usize
        );
    }
    Ok(read.is_ok())
}

/// Overwrites the four integers of the EXR attribute `name` (a box2i).
fn set_box(bytes: &mut [u8], name: &str, values: [i32; 4]) {
    let pattern = [name.as_bytes(), b"\0box2i\0"].concat();
    if let Some(at) = bytes.windows(pattern.len()).position(|w| w == pattern) {
        let start = at + pattern.len() + 4;
        for (k, v) in values.iter().enumerate() {
            bytes[start + 4 * k..start + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
}

#[derive(Clone, Debug)]
enum ExrInput {
    Bytes(Vec<ByteEdit>),
    /// A data or display window of this size, then byte edits.
    Window(bool, [i32; 4], Vec<ByteEdit>),
}

fn box_value() -> impl Strategy<Value = i32> {
    prop_oneof![
        Just(0),
        Just(5),
        Just(-1),
        Just(99_999),
        Just(1 << 20),
        Just(i32::MAX),
        Just(i32::MIN),
        any::<i32>(),
    ]
}

#[test]
fn exr_parts_for_merge_give_an_image_or_an_error() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let valid = std::fs::read(merge_part(dir.path(), "valid.exr")).unwrap();
    let path = dir.path().join("fuzz.exr");
    let edits = || prop::collection::vec(byte_edit(), 0..4);
    let inputs = prop_oneof![
        3 => prop::collection::vec(byte_edit(), 1..6).prop_map(ExrInput::Bytes),
        1 => (any::<bool>(), [box_value(), box_value(), box_value(), box_value()], edits())
            .prop_map(|(data, b, e)| ExrInput::Window(data, b, e)),
    ];
    check("EXR parts", inputs, |input| {
        let mut bytes = valid.clone();
        match &input {
            ExrInput::Bytes(edits) => apply_bytes(&mut bytes, edits),
            ExrInput::Window(data, b, edits) => {
                let name = if *data { "dataWindow" } else { "displayWindow" };
                set_box(&mut bytes, name, *b);
                apply_bytes(&mut bytes, edits);
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        let path = path.clone();
        within("read_with_metadata (EXR)", move || {
            read_image_is_sound(&tracer::film::read::read_with_metadata(&path))
        })?
    });
}

#[derive(Clone, Debug)]
struct PfmInput {
    width: Option<String>,
    height: Option<String>,
    scale: Option<String>,
    data: Vec<ByteEdit>,
    /// `None`: the sidecar as written.
    sidecar: Option<SceneInput>,
}

fn size_token() -> impl Strategy<Value = Option<String>> {
    prop::option::weighted(
        0.3,
        prop::sample::select(
            &[
                "0",
                "1",
                "6",
                "-6",
                "100000",
                "2147483648",
                "4294967295",
                "4294967296",
                "3037000500",
                "x",
                "",
                "1e3",
            ][..],
        )
        .prop_map(str::to_string),
    )
}

#[test]
fn pfm_parts_and_sidecars_for_merge_give_an_image_or_an_error() {
    let _guard = common::heavy();
    let dir = TempDir::new().unwrap();
    let valid_path = merge_part(dir.path(), "valid.pfm");
    let valid = std::fs::read(&valid_path).unwrap();
    let sidecar_text =
        std::fs::read_to_string(tracer::film::metadata::sidecar_path(&valid_path)).unwrap();
    let sidecar: Value = serde_json::from_str(&sidecar_text).unwrap();
    let header_end = valid
        .iter()
        .enumerate()
        .filter(|(_, &b)| b == b'\n')
        .nth(2)
        .unwrap()
        .0
        + 1;
    let path = dir.path().join("fuzz.pfm");
    let side = tracer::film::metadata::sidecar_path(&path);
    let scale = prop::option::weighted(
        0.2,
        prop::sample::select(&["1.0", "-1.0", "nan", "-inf", "0", "-0"][..])
            .prop_map(str::to_string),
    );
    let inputs = (
        size_token(),
        size_token(),
        scale,
        prop_oneof![Just(Vec::new()), prop::collection::vec(byte_edit(), 1..3)],
        prop::option::of(scene_inputs(sidecar.clone())),
    )
        .prop_map(|(width, height, scale, data, sidecar)| PfmInput {
            width,
            height,
            scale,
            data,
            sidecar,
        });
    check("PFM parts with sidecars", inputs, |input| {
        let fields = [&input.width, &input.height, &input.scale];
        let mut bytes = if fields.iter().any(|f| f.is_some()) {
            format!(
                "PF\n{} {}\n{}\n",
                input.width.as_deref().unwrap_or("6"),
                input.height.as_deref().unwrap_or("4"),
                input.scale.as_deref().unwrap_or("-1.0")
            )
            .into_bytes()
            .into_iter()
            .chain(valid[header_end..].iter().copied())
            .collect()
        } else {
            valid.clone()
        };
        apply_bytes(&mut bytes, &input.data);
        std::fs::write(&path, &bytes).unwrap();
        let side_text = match &input.sidecar {
            Some(edits) => scene_text(edits, &sidecar),
            None => sidecar_text.clone(),
        };
        std::fs::write(&side, side_text).unwrap();
        let path = path.clone();
        within("read_with_metadata (PFM)", move || {
            read_image_is_sound(&tracer::film::read::read_with_metadata(&path))
        })?
    });
}

// ---------------------------------------------------------------------------
// Sizes and indices in the billions: a clean error, at once.

/// A header or index asking for a huge size is refused without trying.
#[test]
fn huge_sizes_in_inputs_are_clean_errors() {
    let dir = TempDir::new().unwrap();
    let quick = |what: &'static str, f: Box<dyn FnOnce() -> Result<(), String> + Send>| {
        let result = within(what, f).unwrap_or_else(|e| panic!("{e}"));
        assert!(result.is_err(), "{what}: accepted");
    };

    // An OBJ face naming vertex 4 billion.
    let obj = write(
        &dir.path().join("far.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n",
    );
    quick(
        "OBJ face index 4e9",
        Box::new(move || tracer::format::obj::load_obj(&obj, None).map(|_| ())),
    );

    // PFM headers far larger than their data; 2^31 × 2^31 × 12 bytes is
    // 0 modulo 2^64, which an unchecked product would take for the length
    // of no data at all.
    for (name, header) in [
        ("wide.pfm", "PF\n100000 100000\n-1.0\n"),
        ("wrap.pfm", "PF\n2147483648 2147483648\n-1.0\n"),
        ("max.pfm", "PF\n4294967295 4294967295\n-1.0\n"),
    ] {
        let path = write(&dir.path().join(name), header);
        quick(
            "PFM header",
            Box::new(move || {
                tracer::film::read::read_pfm(&path)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            }),
        );
    }

    // EXRs whose data window claims 10^10 or 2^40 pixels (the decoder
    // allocated the image the header described: 13 TB, an abort).
    for (k, side) in [100_000, 1 << 20].into_iter().enumerate() {
        let exr = merge_part(dir.path(), &format!("huge{k}.exr"));
        let mut bytes = std::fs::read(&exr).unwrap();
        set_box(&mut bytes, "dataWindow", [0, 0, side - 1, side - 1]);
        std::fs::write(&exr, bytes).unwrap();
        quick(
            "EXR data window",
            Box::new(move || {
                tracer::film::read::read_with_metadata(&exr)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            }),
        );
    }

    // Scenes: subdivisions, film and .trs sizes in the billions.
    let scene = |name: &str, value: Value| {
        let path = common::write_json(dir.path(), name, &value);
        quick(
            "scene",
            Box::new(move || {
                tracer::format::read_scene(&path)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            }),
        );
    };
    let camera = json!({ "position": [0, 0, -5], "look_at": [0, 0, 0], "fov": 40 });
    scene(
        "subdivided.json",
        json!({ "camera": camera, "objects": [{ "type": "sphere", "subdivisions": 4000000000u64 }] }),
    );
    scene(
        "wide.json",
        json!({ "camera": camera, "film": { "width": 4294967295u64, "height": 4294967295u64 } }),
    );
    scene(
        "wide.trs",
        json!({
            "Display": { "Type": "PFM", "ResX": 4294967295u64, "ResY": 2 },
            "Camera": { "Type": "Camera", "Position": [0, 0, -3], "fov": 60 }
        }),
    );
}

// ---------------------------------------------------------------------------
// What the fuzzing found, kept as plain tests.

/// `Kd 0.5` is the MTL format's short form of `Kd 0.5 0.5 0.5`; `Kd 0 0`
/// and a bare `Ke` are malformed. tobj panicked on all three (it unwraps
/// the values it found as three); the mesh now loads, the short form with
/// its grey.
#[test]
fn mtl_colours_with_fewer_than_three_values_load() {
    use tracer::format::desc::{AlbedoDesc, MaterialDesc};
    let dir = TempDir::new().unwrap();
    let obj = write(
        &dir.path().join("short.obj"),
        "mtllib short.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\nusemtl odd\nf 1 2 3\n",
    );
    write(
        &dir.path().join("short.mtl"),
        "newmtl grey\nKd 0.25\nKa\nnewmtl odd\n  Kd 0.5 0.75\nKe\n",
    );
    let file = within("load_obj", move || {
        tracer::format::obj::load_obj(&obj, None)
    })
    .unwrap_or_else(|e| panic!("{e}"))
    .unwrap();
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);
    let albedo = |k: usize| match &file.groups[k].material.as_ref().unwrap().desc {
        MaterialDesc::Diffuse {
            albedo: AlbedoDesc::Constant(c),
        } => *c,
        other => panic!("{other:?}"),
    };
    assert_eq!(albedo(0), glam::Vec3::splat(0.25));
    assert_eq!(albedo(1), glam::Vec3::new(0.5, 0.75, 0.75));
}

/// A face's relative normal or texture index before any normal or
/// texture coordinate (`f 1//-2`, `f 1/-5`) made tobj overflow (a panic
/// where overflow is checked, as in the tests): now a clean error naming
/// the file.
#[test]
fn obj_face_indices_before_the_first_normal_are_an_error() {
    let dir = TempDir::new().unwrap();
    for (name, text) in [
        (
            "relative.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//-2 2//-2 3//-2\nvn 0 0 1\n",
        ),
        (
            "texture.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/-5 2/-5 3/-5\nvt 0 0\n",
        ),
    ] {
        let obj = write(&dir.path().join(name), text);
        let result = within("load_obj", move || {
            tracer::format::obj::load_obj(&obj, None).map(|_| ())
        })
        .unwrap_or_else(|e| panic!("{e}"));
        let message = result.expect_err(name);
        assert!(message.contains(name), "{message}");
    }
}
