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
