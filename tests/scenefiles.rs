//! Scene files: every malformed input of `tests/data/bad/` gives a clear error (the file and
//! the offending key/line/value named) and a non-zero exit, never a panic; the files of the
//! built-in scenes in `experiments/scenes/` give the same scene and the same run as their
//! built-in twins.

use contactlab::scene::file;
use contactlab::scene::{balloons, balloons3d, ring, rod, sheets, solids, Scene};
use contactlab::solve::outer::{run, OuterSettings};
use contactlab_solvers::{backend_from_name, QpSettings};
use std::path::Path;
use std::process::Command;

/// Each malformed file, with substrings its error must contain (besides the file's name).
const CORPUS: &[(&str, &[&str])] = &[
    (
        "bad_material.toml",
        &[":4:", "body[0].material.model", "\"rubber\""],
    ),
    ("bad_number_msh.toml", &["bad_number.msh:7", "\"1.0.0\""]),
    (
        "bad_toml_syntax.toml",
        &["bad_toml_syntax.toml:13", "string"],
    ),
    ("binary_msh.toml", &["binary.msh:2", "binary"]),
    (
        "crossing_start.toml",
        &[
            "not admissible",
            "body \"lower\"",
            "body \"upper\"",
            "crossing",
        ],
    ),
    (
        "dangling_index.toml",
        &[":4:", "body[0].elements[1]", "vertex 5 does not exist"],
    ),
    ("dangling_msh.toml", &["dangling.msh:12", "node tag 9"]),
    (
        "dangling_obj.toml",
        &["dangling.obj:3", "vertex reference 9"],
    ),
    ("dim4.toml", &[":1:", "dim = 4"]),
    (
        "duplicate_body.toml",
        &["body[1].name = \"lower\"", "same name"],
    ),
    ("empty.toml", &["missing field `dim`"]),
    ("eps_negative.toml", &[":2:", "eps = -0.001"]),
    (
        "eps_too_large.toml",
        &[
            ":2:",
            "eps = 0.6",
            "larger than the scene can hold",
            "body \"lower\"",
            "5.000000e-1",
        ],
    ),
    ("eps_zero.toml", &[":2:", "eps = 0", "> 0"]),
    (
        "fixed_out_of_range.toml",
        &["body[0].fixed.vertices = 7", "no such vertex"],
    ),
    (
        "gravity_no_density.toml",
        &[":3:", "gravity", "body \"lower\"", "density"],
    ),
    ("huge_coordinate.toml", &["body[0].vertices[1]", "1e200"]),
    (
        "inadmissible_start.toml",
        &[
            "not admissible",
            "vertex 0 of body \"lower\"",
            "5.000000e-3 < eps = 1.000000e-2",
        ],
    ),
    (
        "inf_coordinate.toml",
        &["inf_coordinate.obj:2", "vertex 1", "inf"],
    ),
    (
        "inverted_tet.toml",
        &[
            "inverted_tet.msh:19",
            "tetrahedron 0",
            "inverted",
            "-1.6666666666666666e-1",
        ],
    ),
    (
        "inverted_triangle.toml",
        &["inverted_triangle.obj:4", "triangle 0", "inverted", "-5e-1"],
    ),
    (
        "missing_material.toml",
        &[":4:", "body[0].material", "(missing)"],
    ),
    (
        "missing_mesh_file.toml",
        &[":4:", "body[0].mesh", "does_not_exist.obj", "no such file"],
    ),
    ("nan_coordinate.toml", &["body[0].vertices[1]", "NaN"]),
    ("negative_index.toml", &["body[0].elements[1]", "vertex -2"]),
    ("not_utf8_obj.toml", &["not_utf8.obj:3", "UTF-8"]),
    ("open_gas_surface.toml", &["body[0].gas.c", "not closed"]),
    (
        "surface_in_2d.toml",
        &["body[0].kind", "surface", "dim = 3"],
    ),
    ("unbounded.toml", &[":3:", "unbounded", "body \"falling\""]),
    ("unknown_backend.toml", &["solver.backend", "\"gurobi\""]),
    (
        "solver_bad_newton_model.toml",
        &[
            ":4:",
            "solver.newton_model",
            "\"exact\"",
            "shifted, shifted-tight, projected",
        ],
    ),
    (
        "solver_bad_outer_method.toml",
        &[":4:", "solver.outer_method", "\"newton\"", "pantz, sqp"],
    ),
    (
        "solver_bad_sqp_curvature.toml",
        &[
            ":4:",
            "solver.sqp_curvature",
            "\"hessian\"",
            "off, psd, full, tangent, interior, auto",
        ],
    ),
    (
        "solver_bad_sqp_normal_stiffness.toml",
        &[
            ":4:",
            "solver.sqp_normal_stiffness",
            "-0.5",
            "must be finite and ≥ 0",
        ],
    ),
    ("unknown_body_key.toml", &[":19:", "unknown field `colour`"]),
    ("unknown_contact_body.toml", &["contact.pairs", "\"uper\""]),
    ("unknown_key.toml", &[":3:", "unknown field `epsilon`"]),
    (
        "unknown_statement_obj.toml",
        &["unknown_statement.obj:3", "\"cstype\""],
    ),
    (
        "unused_vertex.toml",
        &["body \"lower\"", "vertex 3", "belongs to no edge"],
    ),
    ("wrong_type.toml", &[":2:", "\"small\""]),
    ("z_in_2d.toml", &["z_in_2d.obj:2", "vertex 1", "z = 0.25"]),
    (
        "weld_unknown_body.toml",
        &[":3:", "weld[0]", "no body is named \"uper\""],
    ),
    (
        "weld_out_of_range.toml",
        &[":3:", "weld[0]", "body \"upper\" has no vertex 3"],
    ),
    (
        "weld_far_apart.toml",
        &[":3:", "weld[0]", "distance 5e-1", "reference configuration"],
    ),
    (
        "weld_same_body.toml",
        &[":3:", "weld[0]", "welds body \"lower\" to itself"],
    ),
    ("weld_wrong_shape.toml", &[":3:", "tuple of size 4"]),
    (
        "weld_chain_folds_body.toml",
        &[":7:", "weld[2]", "merges vertices 0 and 2 of body \"a\""],
    ),
    (
        "dynamics_bad_scheme.toml",
        &[":4:", "dynamics.scheme", "\"rk4\""],
    ),
    (
        "velocity_wrong_length.toml",
        &[
            ":4:",
            "body[0].velocity",
            "[1.0, 0.0, 0.0]",
            "2 finite numbers",
        ],
    ),
    (
        "zero_area_triangle.toml",
        &["zero_area_triangle.msh:12", "triangle 0", "zero area"],
    ),
    (
        "zero_length_edge.toml",
        &["body \"lower\"", "edge 0", "zero length"],
    ),
];

#[test]
fn scenefiles_malformed_corpus_gives_named_errors_and_exit_2() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad");
    // every scene file of the corpus has an expectation
    let mut listed: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    listed.sort();
    let mut expected: Vec<String> = CORPUS.iter().map(|(f, _)| f.to_string()).collect();
    expected.sort();
    assert_eq!(listed, expected, "tests/data/bad and CORPUS disagree");
    let out = std::env::temp_dir().join("contactlab-scenefiles-corpus");
    for (file, needles) in CORPUS {
        let path = dir.join(file);
        let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .args(["run", path.to_str().unwrap(), "--quiet", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{file}: exit {:?}, stderr {err}",
            o.status
        );
        assert!(!err.contains("panicked"), "{file}: {err}");
        // the file at fault is named: the scene file, or the mesh file named in the needles
        let mesh_named = needles
            .iter()
            .any(|n| n.contains(".msh:") || n.contains(".obj:"));
        assert!(mesh_named || err.contains(file), "{file} not named: {err}");
        for n in *needles {
            assert!(err.contains(n), "{file}: {n:?} missing from {err}");
        }
    }
}

#[test]
fn scenefiles_good_file_loads() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/good_strings.toml");
    let f = file::load(&p).unwrap();
    assert_eq!(f.scene.mesh.nv(), 6);
    assert_eq!(f.scene.mesh.edges.len(), 4);
    assert_eq!(f.body_names, vec!["lower", "upper"]);
    assert!(f.scene.mesh.contact_filter.is_none());
    assert_eq!(f.scene.name, "good_strings");
}

fn assert_same_scene(file: &Scene, builtin: &Scene) {
    let (a, b) = (&file.mesh, &builtin.mesh);
    assert_eq!(a.dim, b.dim);
    assert_eq!(a.x_ref, b.x_ref, "reference positions");
    assert_eq!(file.x0, builtin.x0, "initial positions");
    assert_eq!(a.fixed, b.fixed);
    assert_eq!(file.eps, builtin.eps);
    assert_eq!(a.edges.len(), b.edges.len());
    assert_eq!(a.faces.len(), b.faces.len());
    assert_eq!(a.tets, b.tets);
    // the same contact elements (the order may differ)
    let sorted = |mut v: Vec<Vec<usize>>| {
        v.iter_mut().for_each(|e| e.sort_unstable());
        v.sort();
        v
    };
    assert_eq!(
        sorted(a.edges.iter().map(|e| e.to_vec()).collect()),
        sorted(b.edges.iter().map(|e| e.to_vec()).collect())
    );
    assert_eq!(
        sorted(a.faces.iter().map(|e| e.to_vec()).collect()),
        sorted(b.faces.iter().map(|e| e.to_vec()).collect())
    );
    // the same bodies (by name; a scene file may order them differently), each with the same
    // vertex list (a welded vertex listed by every body holding it) and contact elements
    assert_eq!(a.bodies.len(), b.bodies.len());
    for bb in &b.bodies {
        let ba = a
            .bodies
            .iter()
            .find(|x| x.name == bb.name)
            .unwrap_or_else(|| panic!("{}: no body {:?} in the file", builtin.name, bb.name));
        assert_eq!(ba.kind, bb.kind, "{}", bb.name);
        assert_eq!(ba.vertices, bb.vertices, "{}: vertices", bb.name);
        let edges = |m: &contactlab::scene::mesh::Mesh, body: &contactlab::scene::mesh::Body| {
            sorted(body.edges.iter().map(|&e| m.edges[e].to_vec()).collect())
        };
        assert_eq!(edges(a, ba), edges(b, bb), "{}: edges", bb.name);
        let faces = |m: &contactlab::scene::mesh::Mesh, body: &contactlab::scene::mesh::Body| {
            sorted(body.faces.iter().map(|&f| m.faces[f].to_vec()).collect())
        };
        assert_eq!(faces(a, ba), faces(b, bb), "{}: faces", bb.name);
    }
    assert!(
        (file.h - builtin.h).abs() <= 1e-12 * builtin.h,
        "{}: h {} vs {}",
        builtin.name,
        file.h,
        builtin.h
    );
    // J and ∇J at φ_0 and at a perturbed state, to round-off
    let mut y = file.x0.clone();
    for (k, v) in y.iter_mut().enumerate() {
        if !a.fixed[k / a.dim] {
            *v += 1e-3 * ((k * 7919 % 13) as f64 / 13.0 - 0.5);
        }
    }
    for x in [&file.x0, &y] {
        let (ja, jb) = (file.energy.value(x), builtin.energy.value(x));
        assert!(
            (ja - jb).abs() <= 1e-13 * jb.abs().max(1.0),
            "J {ja} vs {jb}"
        );
        let (ga, gb) = (file.energy.gradient(x), builtin.energy.gradient(x));
        let gmax = gb.iter().fold(1.0f64, |m, g| m.max(g.abs()));
        for (p, q) in ga.iter().zip(&gb) {
            assert!((p - q).abs() <= 1e-12 * gmax, "grad {p} vs {q}");
        }
    }
}

fn run_energy(s: &Scene) -> (f64, usize) {
    let mut backend = backend_from_name("clarabel", &QpSettings::default()).unwrap();
    let r = run(
        &s.mesh,
        &s.energy,
        s.eps,
        &s.x0,
        backend.as_mut(),
        &OuterSettings::default(),
        &mut |_, _| {},
    )
    .unwrap();
    (r.energy, r.outer_iterations)
}

fn scene_file(name: &str) -> Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("experiments/scenes")
        .join(format!("{name}.toml"));
    file::load(&p).unwrap().scene
}

#[test]
fn scenefiles_builtin_twins_same_scene_and_run() {
    let twins: Vec<(Scene, Scene)> = vec![
        (
            scene_file("ring"),
            ring::build(&Default::default()).unwrap(),
        ),
        (scene_file("rod"), rod::build(&Default::default()).unwrap()),
        (
            scene_file("sheets"),
            sheets::build(&Default::default()).unwrap(),
        ),
        (
            scene_file("solids"),
            solids::build(&Default::default()).unwrap(),
        ),
        (
            scene_file("balloons"),
            balloons::build(&Default::default()).unwrap(),
        ),
        (
            scene_file("balloons3d"),
            balloons3d::build(&Default::default()).unwrap(),
        ),
    ];
    for (f, b) in &twins {
        assert_same_scene(f, b);
        let (jf, kf) = run_energy(f);
        let (jb, kb) = run_energy(b);
        assert_eq!(kf, kb, "{}: outer iterations", b.name);
        assert!(
            (jf - jb).abs() <= 1e-12 * jb.abs(),
            "{}: final J {jf} vs {jb}",
            b.name
        );
    }
}

#[test]
fn scenefiles_every_experiment_scene_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let f = file::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(f.scene.mesh.nv() > 0);
            n += 1;
        }
    }
    assert_eq!(
        n, 9,
        "ring, rod, sheets, solids, solids_noself, two_strings, balloons, balloons3d, drop"
    );
}

/// Three strings meeting at one point, welded in a chain `a~b, b~c` plus the closing `c~a`:
/// one vertex, numbered where it first occurs (body `a`), listed by the three bodies, fixed
/// because `b` fixes it; the order of the weld entries does not change the mesh.
#[test]
fn scenefiles_weld_chains_and_cycles_are_one_vertex() {
    let text = |welds: &str| {
        format!(
            r#"dim = 2
eps = 0.01
weld = [{welds}]

[[body]]
name = "a"
kind = "curve"
vertices = [[1.0, 0.0], [0.0, 0.0]]
elements = [[0, 1]]
material = {{ model = "string", mu = 1.0 }}
fixed = {{ vertices = [0] }}

[[body]]
name = "b"
kind = "curve"
vertices = [[0.0, 0.0], [-1.0, 0.0]]
elements = [[0, 1]]
material = {{ model = "string", mu = 1.0 }}
fixed = {{ vertices = [0, 1] }}

[[body]]
name = "c"
kind = "curve"
vertices = [[0.0, 1.0], [0.0, 0.0]]
elements = [[0, 1]]
material = {{ model = "string", mu = 1.0 }}
fixed = {{ vertices = [0] }}
"#
        )
    };
    let load = |welds: &str| file::parse(&text(welds), Path::new("chain.toml")).unwrap();
    let chain = load(r#"["a", 1, "b", 0], ["b", 0, "c", 1], ["c", 1, "a", 1]"#);
    let m = &chain.scene.mesh;
    assert_eq!(m.nv(), 4);
    let lists: Vec<&Vec<usize>> = m.bodies.iter().map(|b| &b.vertices).collect();
    assert_eq!(lists, [&vec![0, 1], &vec![1, 2], &vec![3, 1]]);
    assert_eq!(m.x_ref, [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 1.0]);
    assert_eq!(m.fixed, [true, true, true, true]);
    assert_eq!(m.edges, [[0, 1], [1, 2], [3, 1]]);
    for welds in [
        r#"["c", 1, "b", 0], ["a", 1, "c", 1]"#,
        r#"["b", 0, "a", 1], ["c", 1, "b", 0], ["a", 1, "c", 1], ["a", 1, "b", 0]"#,
    ] {
        let other = load(welds);
        let o = &other.scene.mesh;
        assert_eq!(o.x_ref, m.x_ref, "{welds}");
        assert_eq!(o.fixed, m.fixed, "{welds}");
        assert_eq!(o.edges, m.edges, "{welds}");
        let ol: Vec<&Vec<usize>> = o.bodies.iter().map(|b| &b.vertices).collect();
        assert_eq!(ol, lists, "{welds}");
    }
}

#[test]
fn scenefiles_solver_table_applies_and_flags_override_it() {
    // two_strings.toml with a [solver] table that sets every kind of key; the run's
    // summary.json says which values were used
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("solver_table");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let src = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/scenes/two_strings.toml"),
    )
    .unwrap();
    let solver = "[solver]\nbackend = \"uzawa\"\npruning = \"lazy\"\naccuracy = \"low\"\n\
                  max_outer = 4\nmax_inner = 3\ntol_j = 1e-7\nqp_tol = 1e-7\n\
                  lazy_start = 0.5\ntrust_delta0 = 0.5\nwarm_start = false\n\
                  newton_model = \"projected\"\nouter_method = \"sqp\"\n";
    let a = src.find("[solver]").unwrap();
    let b = a + src[a..].find("\n\n").unwrap();
    std::fs::write(
        dir.join("s.toml"),
        format!("{}{}{}", &src[..a], solver, &src[b..]),
    )
    .unwrap();
    let summary = |flags: &[&str]| -> serde_json::Value {
        let out = Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .arg("run")
            .arg(dir.join("s.toml"))
            .args(["--quiet", "--out"])
            .arg(dir.join("run"))
            .args(flags)
            .output()
            .unwrap();
        assert!(
            matches!(out.status.code(), Some(0 | 1)),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(dir.join("run/summary.json")).unwrap())
            .unwrap()
    };
    // the file's values
    let s = summary(&[]);
    assert_eq!(s["backend"], "uzawa");
    assert_eq!(s["pruning"], "lazy");
    assert_eq!(s["accuracy"], "low");
    assert_eq!(s["qp_tol"], 1e-7);
    let set = &s["settings"];
    assert_eq!(set["max_outer"], 4);
    assert_eq!(set["tol_j"], 1e-7);
    assert_eq!(set["lazy_start"], 0.5);
    assert_eq!(set["trust"]["delta0"], 0.5);
    assert_eq!(set["inner"]["max_inner"], 3);
    assert_eq!(set["inner"]["warm_start"], false);
    assert_eq!(set["inner"]["hessian_model"], "projected");
    assert_eq!(s["outer_method"], "sqp");
    assert_eq!(set["method"], "sqp");
    // flags given on the command line win, the rest still come from the file
    let s = summary(&[
        "--backend",
        "clarabel",
        "--max-outer",
        "2",
        "--accuracy",
        "default",
        "--tol-j",
        "1e-9",
    ]);
    assert_eq!(s["backend"], "clarabel");
    assert_eq!(s["accuracy"], "default");
    assert_eq!(s["settings"]["max_outer"], 2);
    assert_eq!(s["settings"]["tol_j"], 1e-9);
    assert_eq!(s["pruning"], "lazy");
    assert_eq!(s["settings"]["inner"]["max_inner"], 3);
    assert_eq!(s["qp_tol"], 1e-7);
    assert_eq!(s["settings"]["inner"]["hessian_model"], "projected");
    assert_eq!(s["outer_method"], "sqp");
    let s = summary(&["--newton-model", "shifted", "--outer-method", "pantz"]);
    assert_eq!(s["settings"]["inner"]["hessian_model"], "shifted");
    assert_eq!(s["outer_method"], "pantz");
    assert_eq!(s["sqp_steps"], 0);
    assert!(s["sqp_from"].is_null());
    let s = summary(&["--outer-method", "auto"]);
    assert_eq!(s["outer_method"], "auto");
    // the SQP phase's first step, or null where Pantz's map stopped at a certified state
    let from = &s["sqp_from"];
    assert!(
        from.is_null() || from.as_u64().is_some_and(|k| k >= 1),
        "sqp_from {from}"
    );
    let s = summary(&["--newton-model", "shifted-tight"]);
    assert_eq!(s["settings"]["inner"]["hessian_model"], "shifted-tight");
}

#[test]
fn scenefiles_solver_sqp_model_keys_apply_and_flags_override_them() {
    // good_strings.toml (static) and dynamic_string.toml (--dynamic), each with a [solver]
    // table that sets the SQP model; summary.json says which values were used
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("solver_sqp_keys");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let solver = "[solver]\nouter_method = \"sqp\"\nsqp_curvature = \"psd\"\n\
                  sqp_normal_stiffness = 0.01\nsqp_drop_endpoint_rows = true\n\
                  sqp_extend_rows = true\nsqp_drop_vertex_rows = true\n\
                  sqp_drop_side_rows = true\n\
                  sqp_path_rows = true\nsqp_implying_rows = true\n\
                  sqp_extrapolate = 2\n\n";
    for name in ["good_strings.toml", "dynamic_string.toml"] {
        let src = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/data")
                .join(name),
        )
        .unwrap();
        // [solver] before the first table (the top-level keys stay first)
        let a = src.find("\n[").unwrap() + 1;
        std::fs::write(
            dir.join(name),
            format!("{}{}{}", &src[..a], solver, &src[a..]),
        )
        .unwrap();
    }
    // `contactlab run FILE --quiet --out DIR/out FLAGS`
    let run = |name: &str, out: &str, flags: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .arg("run")
            .arg(dir.join(name))
            .args(["--quiet", "--out"])
            .arg(dir.join(out))
            .args(flags)
            .output()
            .unwrap()
    };
    let summary = |name: &str, flags: &[&str]| -> serde_json::Value {
        let out = run(name, "run", flags);
        assert!(
            out.status.success(),
            "{name} {flags:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(dir.join("run/summary.json")).unwrap())
            .unwrap()
    };
    let sqp = |s: &serde_json::Value| {
        assert_eq!(s["settings"]["method"], "sqp");
        (
            s["settings"]["sqp"]["curvature"]
                .as_str()
                .unwrap()
                .to_string(),
            s["settings"]["sqp"]["normal_stiffness"].as_f64().unwrap(),
            s["settings"]["sqp"]["drop_endpoint_rows"]
                .as_bool()
                .unwrap(),
            s["settings"]["sqp"]["extend_rows"].as_bool().unwrap(),
            s["settings"]["sqp"]["drop_vertex_rows"].as_bool().unwrap(),
            s["settings"]["sqp"]["drop_side_rows"].as_bool().unwrap(),
            s["settings"]["sqp"]["path_rows"].as_bool().unwrap(),
            s["settings"]["sqp"]["implying_rows"].as_bool().unwrap(),
            s["settings"]["sqp"]["extrapolate"].as_u64().unwrap(),
        )
    };
    for (name, dynamic) in [
        ("good_strings.toml", &[][..]),
        ("dynamic_string.toml", &["--dynamic"][..]),
    ] {
        // the file's values
        assert_eq!(
            sqp(&summary(name, dynamic)),
            ("psd".into(), 0.01, true, true, true, true, true, true, 2),
            "{name}"
        );
        // a flag given on the command line wins, even at its default value; the other key
        // still comes from the file
        let flags = [dynamic, &["--sqp-curvature", "off"]].concat();
        assert_eq!(
            sqp(&summary(name, &flags)),
            ("off".into(), 0.01, true, true, true, true, true, true, 2),
            "{name}"
        );
        let flags = [
            dynamic,
            &[
                "--sqp-curvature",
                "tangent",
                "--sqp-normal-stiffness",
                "0",
                "--sqp-drop-endpoint-rows",
                "false",
                "--sqp-extend-rows",
                "false",
                "--sqp-path-rows",
                "false",
                "--sqp-extrapolate",
                "3",
            ],
        ]
        .concat();
        assert_eq!(
            sqp(&summary(name, &flags)),
            (
                "tangent".into(),
                0.0,
                false,
                false,
                true,
                true,
                false,
                true,
                3
            ),
            "{name}"
        );
        // with the Pantz method (a flag over the file's sqp) the model's settings would be
        // ignored: refused, naming them, whether they come from the file or from a flag
        let refused = |flags: &[&str], needles: &[&str]| {
            let o = run(name, "refused", flags);
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{name} {flags:?}: {err}");
            for n in needles {
                assert!(
                    err.contains(n),
                    "{name} {flags:?}: {n:?} missing from {err}"
                );
            }
        };
        let pantz = [dynamic, &["--outer-method", "pantz"]].concat();
        refused(
            &pantz,
            &[
                "--sqp-curvature psd and --sqp-normal-stiffness 0.01 and \
                 --sqp-drop-endpoint-rows and --sqp-extend-rows and --sqp-drop-vertex-rows and \
                 --sqp-drop-side-rows and --sqp-path-rows and --sqp-implying-rows and \
                 --sqp-extrapolate 2",
                "pantz",
            ],
        );
        let flags = [&pantz[..], &["--sqp-curvature", "off"]].concat();
        refused(
            &flags,
            &[
                "--sqp-normal-stiffness 0.01 and --sqp-drop-endpoint-rows and \
                 --sqp-extend-rows and --sqp-drop-vertex-rows and --sqp-drop-side-rows and \
                 --sqp-path-rows and --sqp-implying-rows and --sqp-extrapolate 2",
                "pantz",
            ],
        );
        let flags = [
            &pantz[..],
            &[
                "--sqp-curvature",
                "off",
                "--sqp-normal-stiffness",
                "0",
                "--sqp-drop-endpoint-rows",
                "false",
                "--sqp-extend-rows",
                "false",
                "--sqp-drop-vertex-rows",
                "false",
                "--sqp-drop-side-rows",
                "false",
                "--sqp-path-rows",
                "false",
                "--sqp-implying-rows",
                "false",
                "--sqp-extrapolate",
                "0",
            ],
        ]
        .concat();
        assert_eq!(
            summary(name, &flags)["settings"]["method"],
            "pantz",
            "{name}"
        );
    }
    // the built-in scenes, from the command line: each SQP setting refused with pantz
    for (flags, out, needle) in [
        (
            &["--outer-method", "pantz", "--sqp-curvature", "full"][..],
            "refused_ring",
            "--sqp-curvature full set with the pantz outer method",
        ),
        (
            &["--outer-method", "pantz", "--sqp-drop-endpoint-rows"][..],
            "refused_ring_drop",
            "--sqp-drop-endpoint-rows set with the pantz outer method",
        ),
        (
            &["--outer-method", "pantz", "--sqp-extend-rows"][..],
            "refused_ring_extend",
            "--sqp-extend-rows set with the pantz outer method",
        ),
        (
            &["--outer-method", "pantz", "--sqp-drop-vertex-rows", "true"][..],
            "refused_ring_vertex",
            "--sqp-drop-vertex-rows set with the pantz outer method",
        ),
        (
            &[
                "--outer-method",
                "pantz",
                "--sqp-extend-rows",
                "--sqp-extend-fixed",
            ][..],
            "refused_ring_extend_fixed",
            "--sqp-extend-rows and --sqp-extend-fixed set with the pantz outer method",
        ),
        (
            &["--outer-method", "sqp", "--sqp-extend-fixed"][..],
            "refused_ring_fixed_alone",
            "--sqp-extend-fixed set without --sqp-extend-rows",
        ),
        (
            &["--outer-method", "pantz", "--sqp-drop-side-rows"][..],
            "refused_ring_side",
            "--sqp-drop-side-rows set with the pantz outer method",
        ),
        (
            &["--outer-method", "pantz", "--sqp-path-rows"][..],
            "refused_ring_path",
            "--sqp-path-rows set with the pantz outer method",
        ),
        (
            &["--outer-method", "pantz", "--sqp-extrapolate", "3"][..],
            "refused_ring_extrapolate",
            "--sqp-extrapolate 3 set with the pantz outer method",
        ),
        (
            &["--outer-method", "auto", "--sqp-extrapolate", "3"][..],
            "refused_ring_auto",
            "--sqp-extrapolate 3 set with the auto outer method",
        ),
        (
            &["--outer-method", "auto", "--sqp-edge-edge-stiffness", "100"][..],
            "refused_ring_auto_edge_edge",
            "--sqp-edge-edge-stiffness 100 set with the auto outer method",
        ),
        (
            &[
                "--outer-method",
                "pantz",
                "--sqp-normal-active-rel",
                "0.001",
            ][..],
            "refused_ring_active_rel",
            "--sqp-normal-active-rel 0.001 set with the pantz outer method",
        ),
        (
            &["--outer-method", "sqp", "--sqp-normal-active-rel", "2"][..],
            "refused_ring_active_rel_range",
            "--sqp-normal-active-rel must be in [0, 1], got 2",
        ),
        (
            &["--outer-method", "sqp", "--sqp-implying-rows"][..],
            "refused_ring_implying",
            "--sqp-implying-rows set without --sqp-drop-endpoint-rows or --sqp-drop-vertex-rows",
        ),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
            .args(["run", "ring", "--n", "12", "--quiet"])
            .args(flags)
            .arg("--out")
            .arg(dir.join(out))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(needle), "{err}");
    }
}
