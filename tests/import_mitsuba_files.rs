//! `poser import` of Mitsuba 3 XML files that poser did not write (issue 37): a parse in
//! linear time, paths resolved on disk (symbolic links included) and kept in the scene's
//! folder, Mitsuba's file resolver (`<path>` folders), the sensor's defaults, emitters
//! referenced by id, no housing when there is none, and every dropped or approximated element
//! named in the notes.

use std::path::Path;
use std::process::{Command, Output};

fn poser() -> Command {
    Command::new(env!("CARGO_BIN_EXE_poser"))
}

/// `poser import FILES -o out/scene.toml`, run in `dir`.
fn import(dir: &Path, files: &[&str]) -> Output {
    poser()
        .current_dir(dir)
        .arg("import")
        .args(files)
        .args(["-o", "out/scene.toml"])
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Import; it must succeed. Returns the scene text.
fn imported(dir: &Path, files: &[&str]) -> String {
    let out = import(dir, files);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::read_to_string(dir.join("out/scene.toml")).unwrap()
}

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

const SENSOR: &str = r#"<sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>"#;

/// A one-rectangle OBJ.
const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n";

fn scene(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<scene version=\"3.0.0\">\n    {SENSOR}\n{body}\n</scene>\n")
}

/// A scene of about a million elements (under MAX_ELEMENTS): one shape with 999 990 `float`
/// children, all on one line (the worst case for counting columns). It imports. The time is
/// not asserted; it is printed (`-- --nocapture`).
#[test]
fn a_million_elements_parse_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let n = 999_990;
    let mut body = String::with_capacity(n * 40);
    body.push_str("<shape type=\"rectangle\">");
    for i in 0..n {
        body.push_str(&format!("<float name=\"p{i}\" value=\"1\"/>"));
    }
    body.push_str("</shape>");
    write(&dir.path().join("big.xml"), &scene(&body));
    let t = std::time::Instant::now();
    let text = imported(dir.path(), &["big.xml"]);
    eprintln!(
        "import of {} elements: {:.2} s",
        n + 6,
        t.elapsed().as_secs_f64()
    );
    assert!(text.contains("shape = \"plane\""), "{text}");

    // One more line of them goes over the cap: refused, with file, line and column.
    let mut over = body.clone();
    over.push_str("\n<shape type=\"rectangle\">");
    for i in 0..20 {
        over.push_str(&format!("<float name=\"q{i}\" value=\"1\"/>"));
    }
    over.push_str("</shape>");
    write(&dir.path().join("over.xml"), &scene(&over));
    let out = import(dir.path(), &["over.xml"]);
    let err = stderr(&out);
    assert!(!out.status.success());
    assert!(
        err.contains("over.xml:9:") && err.contains("more than 1000000 elements"),
        "{err}"
    );
}

/// A link out of the scene's folder is refused, naming the file, line and column of the
/// element that names it; a link inside the folder is followed.
#[cfg(unix)]
#[test]
fn a_symbolic_link_out_of_the_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write(&dir.path().join("outside/secret.obj"), QUAD);
    write(&dir.path().join("scene/meshes/quad.obj"), QUAD);
    std::os::unix::fs::symlink("../outside/secret.obj", dir.path().join("scene/link.obj")).unwrap();
    std::os::unix::fs::symlink("meshes/quad.obj", dir.path().join("scene/inner.obj")).unwrap();
    let shape = |f: &str| {
        scene(&format!(
            "    <shape type=\"obj\">\n        <string name=\"filename\" value=\"{f}\"/>\n    </shape>"
        ))
    };
    write(&dir.path().join("scene/bad.xml"), &shape("link.obj"));
    write(&dir.path().join("scene/good.xml"), &shape("inner.obj"));
    let out = import(dir.path(), &["scene/bad.xml"]);
    let err = stderr(&out);
    assert!(!out.status.success(), "a link out of the folder imported");
    assert!(
        err.contains("scene/bad.xml:9:9") && err.contains("`link.obj` is a symbolic link"),
        "{err}"
    );
    assert!(
        err.contains("outside/secret.obj") && err.contains("help:"),
        "{err}"
    );
    assert!(!dir.path().join("out").exists(), "something was written");

    // An include through a link to a folder outside: refused too.
    std::os::unix::fs::symlink("../outside", dir.path().join("scene/out_dir")).unwrap();
    write(
        &dir.path().join("outside/world.xml"),
        "<scene version=\"3.0.0\"/>",
    );
    write(
        &dir.path().join("scene/inc.xml"),
        &scene("    <include filename=\"out_dir/world.xml\"/>"),
    );
    let err = stderr(&import(dir.path(), &["scene/inc.xml"]));
    assert!(
        err.contains("scene/inc.xml:8:5") && err.contains("symbolic link"),
        "{err}"
    );

    let text = imported(dir.path(), &["scene/good.xml"]);
    assert!(text.contains("shape = \"mesh\""), "{text}");
}

/// `include` and `filename` are looked for in the including file's folder, then in the
/// `<path>` folders, then in the main file's folder; never outside the first file's folder.
#[test]
fn files_are_found_as_mitsubas_resolver_finds_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A mesh in a `<path>` folder, named from an included file in another folder.
    write(&d.join("assets/meshes/quad.obj"), QUAD);
    // An include in `parts/` that names a file beside the main file.
    write(
        &d.join("parts/world.xml"),
        "<scene version=\"3.0.0\">\n    <include filename=\"lights.xml\"/>\n    <shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/></shape>\n</scene>\n",
    );
    write(
        &d.join("lights.xml"),
        "<scene version=\"3.0.0\"><emitter type=\"point\"><point name=\"position\" value=\"0, 0, 3\"/><rgb name=\"intensity\" value=\"4\"/></emitter></scene>\n",
    );
    write(
        &d.join("main.xml"),
        &scene("    <path value=\"assets/meshes\"/>\n    <include filename=\"parts/world.xml\"/>"),
    );
    let text = imported(d, &["main.xml"]);
    let glb_size = || {
        let v: Vec<u64> = std::fs::read_dir(d.join("out/scene_assets"))
            .unwrap()
            .map(|e| e.unwrap().metadata().unwrap().len())
            .collect();
        assert_eq!(v.len(), 1, "one mesh");
        v[0]
    };
    let quad = glb_size();
    assert!(
        text.contains("shape = \"mesh\""),
        "the mesh of the <path> folder: {text}"
    );
    assert!(
        text.contains("type = \"point\""),
        "the light beside the main file: {text}"
    );
    assert!(!text.contains("<path>"), "{text}");

    // The including file's folder comes first: a quad.obj in parts/ is taken before the
    // <path> folder's (it is a triangle: its mesh is not the same).
    write(
        &d.join("parts/quad.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    imported(d, &["main.xml"]);
    assert!(glb_size() < quad, "the triangle of parts/ is taken");

    // A <path> out of the folder is refused, and one that does not exist is named.
    write(&d.join("sub/up.xml"), &scene("    <path value=\"../..\"/>"));
    let err = stderr(&import(d, &["sub/up.xml"]));
    assert!(
        err.contains("sub/up.xml:8:5") && err.contains("leaves the scene's folder"),
        "{err}"
    );
    write(&d.join("nope.xml"), &scene("    <path value=\"nowhere\"/>"));
    let err = stderr(&import(d, &["nope.xml"]));
    assert!(
        err.contains("nope.xml:8:5") && err.contains("`nowhere` not found"),
        "{err}"
    );
    // A file found nowhere: the error names it where the element is.
    write(
        &d.join("missing.xml"),
        &scene("    <shape type=\"obj\"><string name=\"filename\" value=\"gone.obj\"/></shape>"),
    );
    let err = stderr(&import(d, &["missing.xml"]));
    assert!(
        err.contains("missing.xml:8:5") && err.contains("gone.obj"),
        "{err}"
    );
}

/// The value of `key` in the scene text's table `[table]` (first match).
fn value_in(text: &str, table: &str, key: &str) -> Option<String> {
    let start = text.find(&format!("\n[{table}]\n"))?;
    let body = &text[start + table.len() + 4..];
    let body = &body[..body.find("\n[").unwrap_or(body.len())];
    body.lines()
        .find_map(|l| l.strip_prefix(&format!("{key} = ")))
        .map(str::to_string)
}

fn float_in(text: &str, table: &str, key: &str) -> f64 {
    value_in(text, table, key)
        .unwrap_or_else(|| panic!("no {table}.{key} in\n{text}"))
        .parse()
        .unwrap()
}

/// A perspective sensor without `fov`: Mitsuba's `parse_fov` (src/render/sensor.cpp) gives a
/// 50 mm lens on 35 mm film along the diagonal; `focal_length = "28mm"` likewise; the film is
/// 768 × 576 when it gives no size.
#[test]
fn the_sensor_gets_mitsubas_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let body = |sensor: &str| {
        format!(
            "<?xml version=\"1.0\"?>\n<scene version=\"3.0.0\">\n{sensor}\n    <shape type=\"rectangle\"/>\n</scene>\n"
        )
    };
    let diag_fx = |mm: f64, w: f64, h: f64| {
        let fov = 2.0 * (36f64.hypot(24.0) / (2.0 * mm)).atan();
        w.hypot(h) / 2.0 / (fov / 2.0).tan()
    };
    write(
        &d.join("bare.xml"),
        &body("    <sensor type=\"perspective\"/>"),
    );
    let text = imported(d, &["bare.xml"]);
    assert_eq!(value_in(&text, "camera", "width").as_deref(), Some("768"));
    assert_eq!(value_in(&text, "camera", "height").as_deref(), Some("576"));
    let fx = float_in(&text, "camera", "fx");
    assert!(
        (fx / diag_fx(50.0, 768.0, 576.0) - 1.0).abs() < 1e-12,
        "{fx}"
    );
    assert!(text.contains("neither `fov` nor `focal_length`"), "{text}");

    // focal_length as a string, with fov_axis (not read with a focal length).
    write(
        &d.join("f28.xml"),
        &body(
            "    <sensor type=\"perspective\"><string name=\"focal_length\" value=\"28mm\"/><string name=\"fov_axis\" value=\"y\"/>\n        <film type=\"hdrfilm\"><integer name=\"width\" value=\"300\"/><integer name=\"height\" value=\"200\"/><rfilter type=\"box\"/></film></sensor>",
        ),
    );
    let text = imported(d, &["f28.xml"]);
    let fx = float_in(&text, "camera", "fx");
    assert!(
        (fx / diag_fx(28.0, 300.0, 200.0) - 1.0).abs() < 1e-12,
        "{fx}"
    );
    assert!(
        !text.contains("reconstruction filter"),
        "a box filter is poser's: {text}"
    );

    // Both, or a focal length that is not one: refused with the place and a hint.
    write(
        &d.join("both.xml"),
        &body(
            "    <sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/><string name=\"focal_length\" value=\"28mm\"/></sensor>",
        ),
    );
    let err = stderr(&import(d, &["both.xml"]));
    assert!(
        err.contains("both.xml:3:")
            && err.contains("both `fov` and `focal_length`")
            && err.contains("help:"),
        "{err}"
    );
    write(
        &d.join("bad.xml"),
        &body(
            "    <sensor type=\"perspective\"><string name=\"focal_length\" value=\"wide\"/></sensor>",
        ),
    );
    let err = stderr(&import(d, &["bad.xml"]));
    assert!(
        err.contains("bad.xml:3:") && err.contains("focal_length `wide`"),
        "{err}"
    );
}

/// Emitters (and BSDFs, media) referenced by id come in wherever they are referenced: an area
/// emitter defined at the top level and referenced in a rectangle lights the scene, a
/// top-level reference to an emitter defined inside another element is read, and an unknown
/// id is refused where it is named.
#[test]
fn references_are_followed_wherever_an_element_is_expected() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        &d.join("refs.xml"),
        &scene(
            r#"    <emitter type="area" id="lamp"><rgb name="radiance" value="7, 8, 9"/></emitter>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
    <shape type="rectangle" id="panel">
        <transform name="to_world"><translate z="2"/></transform>
        <ref id="lamp"/>
    </shape>
    <shape type="rectangle"><ref id="red"/></shape>
    <shape type="sphere">
        <bsdf type="diffuse"/>
        <emitter type="point" id="inner"><point name="position" value="0, 0, 1"/><rgb name="intensity" value="3"/></emitter>
    </shape>
    <ref id="inner"/>"#,
        ),
    );
    let text = imported(d, &["refs.xml"]);
    assert!(text.contains("type = \"area\""), "{text}");
    assert!(text.contains("radiance = [7.0, 8.0, 9.0]"), "{text}");
    assert!(text.contains("albedo = [0.8, 0.1, 0.1]"), "{text}");
    assert!(text.contains("intensity = [3.0, 3.0, 3.0]"), "{text}");
    assert!(!text.contains("emitter is not imported"), "{text}");
    assert!(!text.contains("BSDF is imported as diffuse"), "{text}");

    write(
        &d.join("unknown.xml"),
        &scene("    <shape type=\"rectangle\"><ref id=\"nope\"/></shape>"),
    );
    let err = stderr(&import(d, &["unknown.xml"]));
    assert!(
        err.contains("unknown.xml:8:29")
            && err.contains("no element has id `nope`")
            && err.contains("help:"),
        "{err}"
    );
    // A cycle is refused, not followed for ever.
    write(
        &d.join("cycle.xml"),
        &scene(
            "    <bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf>\n    <shape type=\"rectangle\"><ref id=\"a\"/></shape>",
        ),
    );
    let out = import(d, &["cycle.xml"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("cycle"), "{}", stderr(&out));
}

/// No glass at the camera: the scene says `[camera.port] type = "none"`, so poser's default
/// flat port (in water) does not appear. A `port = none` scene compiled to Mitsuba and
/// imported back keeps no port.
#[test]
fn no_housing_when_there_is_none() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        &d.join("sea.xml"),
        &format!(
            "<?xml version=\"1.0\"?>\n<scene version=\"3.0.0\">\n{}\n</scene>\n",
            r#"    <sensor type="perspective"><float name="fov" value="45"/><ref id="sea"/>
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, -7" up="0, 1, 0"/></transform></sensor>
    <medium type="homogeneous" id="sea"><rgb name="sigma_t" value="0.2"/><float name="albedo" value="0.5"/></medium>
    <shape type="rectangle"><transform name="to_world"><translate z="-7"/></transform></shape>"#,
        ),
    );
    let text = imported(d, &["sea.xml"]);
    assert_eq!(
        value_in(&text, "camera.port", "type").as_deref(),
        Some("\"none\""),
        "{text}"
    );

    // poser → Mitsuba → poser with port = none: no glass is written, none comes back.
    write(
        &d.join("rt/none.toml"),
        r#"name = "none"
[site]
depth = "10 m"
surface = "none"
[water]
ior = 1.34
absorption = [0.05, 0.04, 0.03]
scattering = [0.0, 0.0, 0.0]
[camera]
width = 80
height = 60
fx = 70.0
[camera.port]
type = "none"
[[lights]]
type = "ambient"
radiance = 1.0
[[objects]]
name = "floor"
shape = "plane"
width = 4.0
height = 4.0
position = [0.0, 0.0, -8.0]
albedo = 0.5
[network]
type = "explicit"
[[network.poses]]
position = [0.0, 0.0, -5.0]
look_at = [0.0, 0.0, -8.0]
up = [0.0, 1.0, 0.0]
"#,
    );
    let model = poser::scene::load(&d.join("rt/none.toml"), &[])
        .map_err(|e| e.render())
        .unwrap()
        .model;
    assert!(matches!(
        model.cameras[0].port,
        poser::optics::types::Port::None
    ));
    let out = poser()
        .args(["compile", "--backend", "mitsuba", "-o"])
        .arg(d.join("rt/mi"))
        .arg(d.join("rt/none.toml"))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("rt/mi/manifest.json")).unwrap()).unwrap();
    let xml = manifest["views"][0]["passes"][0]["xml"]
        .as_str()
        .unwrap()
        .to_string();
    let out = poser()
        .current_dir(d.join("rt"))
        .arg("import")
        .arg(Path::new("mi").join(&xml))
        .args(["-o", "back.toml"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(d.join("rt/back.toml")).unwrap();
    assert_eq!(
        value_in(&text, "camera.port", "type").as_deref(),
        Some("\"none\""),
        "{text}"
    );
    let back = poser::scene::load(&d.join("rt/back.toml"), &[])
        .map_err(|e| e.render())
        .unwrap()
        .model;
    assert!(
        matches!(back.cameras[0].port, poser::optics::types::Port::None),
        "the port came back as {:?}",
        back.cameras[0].port
    );
}

/// Elements with non-default values that poser cannot hold exactly: each is honoured or
/// named in the notes (with its file, line and column).
#[test]
fn every_approximation_is_named_in_the_notes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(
        &d.join("parts/settings.xml"),
        "<scene version=\"3.0.0\">\n    <integrator type=\"volpath\"><integer name=\"max_depth\" value=\"9\"/></integrator>\n</scene>\n",
    );
    write(
        &d.join("approx.xml"),
        r#"<?xml version="1.0"?>
<scene version="3.0.0">
    <include filename="parts/settings.xml"/>
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="64"/><integer name="height" value="48"/>
            <rfilter type="gaussian"><float name="stddev" value="0.7"/></rfilter>
        </film>
    </sensor>
    <shape type="rectangle">
        <bsdf type="diffuse">
            <texture type="checkerboard" name="reflectance">
                <rgb name="color0" value="0.8, 0.2, 0.2"/>
                <rgb name="color1" value="0.2, 0.2, 0.8"/>
            </texture>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.05"/><translate z="4.9"/></transform>
        <bsdf type="dielectric">
            <rgb name="int_ior" value="1.51, 1.52, 1.53"/>
            <string name="ext_ior" value="water"/>
        </bsdf>
    </shape>
</scene>
"#,
    );
    let text = imported(d, &["approx.xml"]);
    // The Gaussian filter, where it is written.
    assert!(
        text.contains("approx.xml:9:13: the film's `gaussian` reconstruction filter"),
        "{text}"
    );
    // The checkerboard: the mean of its colours, noted.
    assert!(text.contains("albedo = [0.5, 0.2, 0.5]"), "{text}");
    assert!(
        text.contains("approx.xml:14:13: a checkerboard texture is imported as the mean"),
        "{text}"
    );
    // The index per channel: one constant, noted.
    assert!(
        text.contains("approx.xml:23:13: `int_ior` per channel (1.5100, 1.5200, 1.5300) is imported as one constant, their mean 1.5200"),
        "{text}"
    );
    // The port note gives the index it read (the mean).
    assert!(text.contains("glass and housing"), "{text}");
    // max_depth of the included file: 9 vertices = the camera, 2 glass faces, 6 bounces.
    assert_eq!(
        value_in(&text, "render", "bounces").as_deref(),
        Some("6"),
        "{text}"
    );
    // A named index that Mitsuba does not know is refused, named.
    std::fs::write(
        d.join("approx.xml"),
        std::fs::read_to_string(d.join("approx.xml"))
            .unwrap()
            .replace("value=\"water\"", "value=\"unobtainium\""),
    )
    .unwrap();
    let err = stderr(&import(d, &["approx.xml"]));
    assert!(
        err.contains("approx.xml:24:13") && err.contains("`unobtainium`"),
        "{err}"
    );
}

/// A sampled spectrum becomes the colour Mitsuba 3's RGB variants give it, not its grey mean:
/// a red wall stays red, a flat 0.5 stays 0.5, and the conversion is noted.
#[test]
fn sampled_spectra_keep_their_colour() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(&d.join("flat.spd"), "# a flat spectrum\n360 0.5\n830 0.5\n");
    write(
        &d.join("spectra.xml"),
        &scene(
            r#"    <shape type="rectangle" id="red">
        <bsdf type="diffuse"><spectrum name="reflectance" value="400:0.04, 500:0.05, 550:0.06, 600:0.55, 650:0.62, 700:0.63"/></bsdf>
    </shape>
    <shape type="rectangle" id="grey">
        <bsdf type="diffuse"><spectrum name="reflectance" filename="flat.spd"/></bsdf>
    </shape>"#,
        ),
    );
    let text = imported(d, &["spectra.xml"]);
    let t: toml::Table = toml::from_str(&text).unwrap();
    let albedo = |name: &str| -> Vec<f64> {
        let o = t["objects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["name"].as_str() == Some(name))
            .unwrap();
        o["albedo"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect()
    };
    let red = albedo("red");
    assert!(
        red[0] > red[1] && red[0] > red[2] && red[0] > 0.3,
        "{red:?}"
    );
    let grey = albedo("grey");
    for c in &grey {
        assert!((c - 0.5).abs() < 1e-3, "{grey:?}");
    }
    assert!(
        text.contains(
            "spectra.xml:9:30: a sampled spectrum (6 samples) is imported as linear sRGB"
        ),
        "{text}"
    );
}

/// A 64 × 32 sRGB PNG: the top half red, the bottom half blue, the 8 left columns green.
fn three_colour_png(path: &Path) {
    let img = image::RgbImage::from_fn(64, 32, |x, y| {
        if x < 8 {
            image::Rgb([30, 220, 30])
        } else if y < 16 {
            image::Rgb([220, 30, 30])
        } else {
            image::Rgb([30, 30, 220])
        }
    });
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    img.save(path).unwrap();
}

/// The dominant channel of the rendered image's pixel (x, y).
fn dominant(img: &poser::image::Linear, x: u32, y: u32) -> usize {
    let p = img.rgb[(y * img.width + x) as usize];
    (0..3).max_by(|&a, &b| p[a].total_cmp(&p[b])).unwrap()
}

/// A bitmap reflectance on an OBJ with `vt`, on a PLY with `u v` and on a rectangle becomes the
/// mesh's image texture: the image is copied beside the `.glb`, the texture coordinates are
/// read as Mitsuba reads them (OBJ's v from the bottom row; a rectangle's uv = (x + 1)/2,
/// (y + 1)/2), and the native render shows the image the way Mitsuba 3 renders the same file
/// (red on top on the meshes, at the bottom on the rectangle; green at the left). A mesh without texture coordinates keeps the
/// mean colour, noted; an image whose header claims 100 000 pixels a side is refused.
#[test]
fn bitmaps_become_image_textures_on_meshes() {
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nproperty float u\nproperty float v\nelement face 2\n\
               property list uchar int vertex_indices\nend_header\n\
               -1 -1 0 0 1\n1 -1 0 1 1\n1 1 0 1 0\n-1 1 0 0 0\n3 0 1 2\n3 0 2 3\n";
    let obj = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    let bitmap = r#"<bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="tex/three.png"/></texture></bsdf>"#;
    let light = r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#;
    for (shape, extra) in [
        (
            r#"<shape type="obj"><string name="filename" value="quad.obj"/>"#,
            ("quad.obj", obj),
        ),
        (
            r#"<shape type="ply"><string name="filename" value="quad.ply"/>"#,
            ("quad.ply", ply),
        ),
        (r#"<shape type="rectangle">"#, ("unused.txt", "")),
    ] {
        let dir = tempfile::tempdir().unwrap();
        three_colour_png(&dir.path().join("tex/three.png"));
        write(&dir.path().join(extra.0), extra.1);
        write(
            &dir.path().join("s.xml"),
            &scene(&format!("{light}\n{shape}{bitmap}</shape>")),
        );
        let text = imported(dir.path(), &["s.xml"]);
        assert!(text.contains("shape = \"mesh\""), "{text}");
        assert!(
            text.contains("is imported as the image texture of"),
            "{text}"
        );
        assert!(!text.contains("mean albedo"), "{text}");
        let png = std::fs::read_dir(dir.path().join("out/scene_assets"))
            .unwrap()
            .filter_map(|e| e.ok())
            .find(|e| e.path().extension().is_some_and(|x| x == "png"))
            .expect("the image beside the mesh");
        assert_eq!(
            std::fs::read(png.path()).unwrap(),
            std::fs::read(dir.path().join("tex/three.png")).unwrap(),
            "an 8-bit sRGB PNG is copied as it is"
        );
        let out = poser()
            .current_dir(dir.path())
            .args(["render", "out/scene.toml", "-o", "r", "--quiet"])
            .args(["--set", "render.daylight=\"traced\"", "--samples", "4"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        let img = poser::image::read_exr(&dir.path().join("r/img_0001.exr")).unwrap();
        // The camera, 5 m away, looks down −z with +y up: the quad spans x 17–47, y 9–39 of the
        // 64 × 48 view; the green columns are x 17–20.
        // Mitsuba's rectangle has v = 0 at its bottom edge (local y = −1), where the image's
        // first (red) row lands; the meshes' coordinates put it on top. Mitsuba 3 renders both
        // so (checked with scalar_rgb).
        let (top, below) = if shape.contains("rectangle") {
            (2, 0)
        } else {
            (0, 2)
        };
        assert_eq!(dominant(&img, 32, 14), top, "{shape}: top");
        assert_eq!(dominant(&img, 32, 34), below, "{shape}: below");
        assert_eq!(dominant(&img, 18, 24), 1, "{shape}: green at the left");
    }

    // No texture coordinates: the mean colour, noted.
    let dir = tempfile::tempdir().unwrap();
    three_colour_png(&dir.path().join("tex/three.png"));
    write(&dir.path().join("quad.obj"), QUAD);
    write(
        &dir.path().join("s.xml"),
        &scene(&format!(
            "{light}\n<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/>{bitmap}</shape>"
        )),
    );
    let text = imported(dir.path(), &["s.xml"]);
    assert!(text.contains("has no texture coordinates"), "{text}");
    assert!(text.contains("mean albedo"), "{text}");

    // A header claiming 100 000 pixels a side: refused before decoding.
    let dir = tempfile::tempdir().unwrap();
    let mut bomb = Vec::new();
    image::RgbImage::new(1, 1)
        .write_to(
            &mut std::io::Cursor::new(&mut bomb),
            image::ImageFormat::Png,
        )
        .unwrap();
    bomb[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    bomb[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32(&bomb[12..29]);
    bomb[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::create_dir_all(dir.path().join("tex")).unwrap();
    std::fs::write(dir.path().join("tex/three.png"), &bomb).unwrap();
    write(&dir.path().join("quad.obj"), obj);
    write(
        &dir.path().join("s.xml"),
        &scene(&format!(
            "{light}\n<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/>{bitmap}</shape>"
        )),
    );
    let out = import(dir.path(), &["s.xml"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("100000"), "{}", stderr(&out));
}

/// CRC-32 (ISO 3309, as PNG chunks carry it).
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}
