//! The control/check split of `poser evaluate --gcp`: which target point is a control point
//! (its truth enters the similarity to the truth, or the bundle adjustment itself with
//! `--gcp-sigma`), which a check point (held out of both, only measured), and every
//! reconstructed point's error after that similarity.
//!
//! | item | meaning |
//! |---|---|
//! | [`Role`], [`target_role`] | a target point's role under `--gcp IDS` and `--check IDS` |
//! | [`check_target_names`] | every id names a target, and none is both control and check |
//! | [`align`] | the similarity fitted on the control points (`--gcp`) or on all points |
//! | [`priors`] | the control points weighted in the adjustment (`--gcp-sigma`): their truth and σ, and nothing of a check point |
//! | [`residuals`] | each point's error after it, sorted into tie, control and check sets |

use super::align::Similarity;
use super::colmap::RequestGcp;
use super::observe::{PointKind, SurveyPoint};
use super::{Options, PointError};
use glam::DVec3;

/// What a target point does in a `--gcp` evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Its truth enters the alignment.
    Control,
    /// Held out of the alignment; its error measures the model's accuracy.
    Check,
    /// Named by neither list when both are given.
    Unused,
}

/// Whether a target point's `label` (`name`, `name/point` or `file/id`) is named by `id`: the
/// whole label, its target (`name` of `name/…`), or its point (`…/id`).
fn names(label: &str, id: &str) -> bool {
    label == id
        || label.strip_prefix(id).is_some_and(|r| r.starts_with('/'))
        || label.rsplit('/').next() == Some(id)
}

/// A target point's role under `opts.control` and `opts.check` (see [`Options::control`]).
pub fn target_role(label: &str, opts: &Options) -> Role {
    let in_control = opts.control.iter().any(|id| names(label, id));
    let in_check = opts.check.iter().any(|id| names(label, id));
    match (opts.control.is_empty(), opts.check.is_empty()) {
        (true, true) => Role::Control,
        (true, false) if in_check => Role::Check,
        (true, false) => Role::Control,
        (false, _) if in_control => Role::Control,
        (false, true) => Role::Check,
        (false, false) if in_check => Role::Check,
        (false, false) => Role::Unused,
    }
}

/// Every id of `--gcp IDS` and `--check IDS` names a target, and none is in both.
pub fn check_target_names(points: &[SurveyPoint], opts: &Options) -> Result<(), String> {
    let labels: Vec<&str> = points
        .iter()
        .filter(|p| p.kind == PointKind::Target)
        .map(|p| p.label.as_str())
        .collect();
    for (flag, ids) in [("--gcp", &opts.control), ("--check", &opts.check)] {
        for id in ids {
            if !labels.iter().any(|l| names(l, id)) {
                let known: Vec<&str> = labels.iter().take(8).copied().collect();
                return Err(format!(
                    "{flag}: no target is named `{id}`\n  help: the scene's target points are \
                     {}{} (a target's name selects all of its points)",
                    known.join(", "),
                    if labels.len() > known.len() {
                        ", …"
                    } else {
                        ""
                    }
                ));
            }
        }
    }
    if let Some(id) = opts.control.iter().find(|id| {
        labels
            .iter()
            .any(|l| names(l, id) && opts.check.iter().any(|c| names(l, c)))
    }) {
        return Err(format!(
            "`{id}` is both a control point (--gcp) and a check point (--check)\n  help: a \
             check point must stay out of the alignment to measure it"
        ));
    }
    Ok(())
}

/// The similarity taking the reconstruction onto the truth, and what it was fitted on.
#[derive(Debug, Clone, Copy)]
pub struct Alignment {
    /// `"gcp"` or `"all points"`.
    pub name: &'static str,
    /// How many points the similarity was fitted on.
    pub count: usize,
    pub sim: Similarity,
}

/// Fit the similarity on the reconstructed `pairs` (`(index into points, reconstructed
/// position)`): with `opts.gcp`, on the control points only, so a check point's truth never
/// reaches it; else on every point.
pub fn align(
    points: &[SurveyPoint],
    pairs: &[(usize, DVec3)],
    opts: &Options,
) -> Result<Alignment, String> {
    let (name, fit_set): (&'static str, Vec<&(usize, DVec3)>) = if opts.gcp {
        check_target_names(points, opts)?;
        let control: Vec<&(usize, DVec3)> = pairs
            .iter()
            .filter(|(k, _)| {
                points[*k].kind == PointKind::Target
                    && target_role(&points[*k].label, opts) == Role::Control
            })
            .collect();
        if control.len() < 3 {
            return Err(format!(
                "--gcp: only {} control point(s) were reconstructed; at least 3 are needed\n  \
                 help: add targets (coded targets, a points file) inside the surveyed area, \
                 name more of them as control points, or drop --gcp to align on all points",
                control.len()
            ));
        }
        ("gcp", control)
    } else {
        ("all points", pairs.iter().collect())
    };
    let from: Vec<DVec3> = fit_set.iter().map(|(_, x)| *x).collect();
    let to: Vec<DVec3> = fit_set.iter().map(|(k, _)| points[*k].world).collect();
    let sim = Similarity::estimate(&from, &to)
        .ok_or("the reconstructed points are degenerate (collinear); no similarity to the truth")?;
    Ok(Alignment {
        name,
        count: fit_set.len(),
        sim,
    })
}

/// The control points that enter the bundle adjustment as weighted constraints
/// (`--gcp-sigma`): each control target point seen in two or more images (`seen[k]` images),
/// as request point `k + 1` known at its truth to `sigma` m. A check point's truth is never
/// in it, so it reaches neither the adjustment nor the datum.
pub fn priors(
    points: &[SurveyPoint],
    seen: &[u32],
    opts: &Options,
    sigma: f64,
) -> Result<Vec<RequestGcp>, String> {
    check_target_names(points, opts)?;
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(format!(
            "--gcp-sigma {sigma}: expected the control points' accuracy in metres, > 0\n  help: \
             e.g. `--gcp-sigma 0.002` for targets surveyed to 2 mm"
        ));
    }
    let out: Vec<RequestGcp> = points
        .iter()
        .enumerate()
        .filter(|(k, p)| {
            seen.get(*k).is_some_and(|&n| n >= 2)
                && p.kind == PointKind::Target
                && target_role(&p.label, opts) == Role::Control
        })
        .map(|(k, p)| RequestGcp {
            id: k as u64 + 1,
            xyz: p.world.to_array(),
            sigma,
        })
        .collect();
    if out.len() < 3 {
        return Err(format!(
            "--gcp-sigma: only {} control point(s) are seen in two or more images; weighting \
             them in the adjustment needs at least 3\n  help: add targets (coded targets, a \
             points file) inside the surveyed area, name more of them as control points, or \
             drop --gcp-sigma to align on them",
            out.len()
        ));
    }
    Ok(out)
}

/// Every reconstructed point's error after the alignment, and the sets the report sums.
#[derive(Debug, Clone, Default)]
pub struct Residuals {
    /// One per reconstructed point, kind `tie`, `gcp` (control), `check` or `target` (unused).
    pub point_errors: Vec<PointError>,
    pub tie: Vec<DVec3>,
    pub control: Vec<DVec3>,
    /// Check points; without `--gcp`, every target (none entered the alignment as such).
    pub check: Vec<DVec3>,
    /// `(x, y, dz)` of the tie points, for the bowl.
    pub bowl_samples: Vec<(f64, f64, f64)>,
}

/// The error (aligned reconstruction − truth) of every point of `pairs` after `sim`; `track`
/// gives a point's number of images by its 1-based id.
pub fn residuals(
    points: &[SurveyPoint],
    pairs: &[(usize, DVec3)],
    sim: &Similarity,
    opts: &Options,
    track: impl Fn(u64) -> u32,
) -> Residuals {
    let mut r = Residuals::default();
    for (k, x) in pairs {
        let p: &SurveyPoint = &points[*k];
        let e = sim.apply(*x) - p.world;
        let kind = match (&p.kind, opts.gcp) {
            (PointKind::Tie, _) => "tie",
            (PointKind::Target, true) => match target_role(&p.label, opts) {
                Role::Control => "gcp",
                Role::Check => "check",
                Role::Unused => "target",
            },
            (PointKind::Target, false) => "target",
        };
        match kind {
            "tie" => {
                r.tie.push(e);
                r.bowl_samples.push((p.world.x, p.world.y, e.z));
            }
            "gcp" => r.control.push(e),
            "check" => r.check.push(e),
            "target" if !opts.gcp => r.check.push(e),
            _ => {}
        }
        r.point_errors.push(PointError {
            id: *k as u64 + 1,
            label: p.label.clone(),
            kind,
            truth: p.world.to_array(),
            error: e.to_array(),
            track: track(*k as u64 + 1),
        });
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// Seven targets as on the lessons' reef plot (corners and middle of a 20 × 7 m block) and
    /// 40 tie points; the "reconstruction" is the truth bent by a bowl of a few centimetres
    /// (what a self-calibrated flat-port block gives), then moved by an arbitrary similarity.
    fn block() -> (Vec<SurveyPoint>, Vec<(usize, DVec3)>) {
        let target = |name: &str, x: f64, y: f64| SurveyPoint {
            world: DVec3::new(x, y, -9.7),
            normal: DVec3::Z,
            kind: PointKind::Target,
            label: format!("{name}/1"),
        };
        let mut points = vec![
            target("gcp_w2", -2.8, -8.0),
            target("gcp_e2", 2.8, -8.0),
            target("gcp_w3", -2.8, 8.0),
            target("gcp_e3", 2.8, 8.0),
            target("gcp_w0", -1.2, -1.0),
            target("gcp_e0", 1.2, 1.0),
            target("gcp_n0", -0.5, 3.5),
        ];
        for i in 0..40 {
            let f = i as f64;
            points.push(SurveyPoint {
                world: DVec3::new(3.0 * (f * 1.3).sin(), 9.0 * (f * 0.7).cos(), -10.0),
                normal: DVec3::Z,
                kind: PointKind::Tie,
                label: "seabed".into(),
            });
        }
        let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.2, -0.1, 0.9);
        let pairs = points
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let w = p.world;
                let bent = w + DVec3::Z * (0.0008 * (w.x * w.x + w.y * w.y) - 0.03);
                (k, 0.37 * (q * bent) + DVec3::new(4.0, -1.0, 2.0))
            })
            .collect();
        (points, pairs)
    }

    fn split() -> Options {
        Options {
            gcp: true,
            control: ["gcp_w2", "gcp_e2", "gcp_w3", "gcp_e3"]
                .map(String::from)
                .into(),
            check: ["gcp_w0", "gcp_e0", "gcp_n0"].map(String::from).into(),
            ..Options::default()
        }
    }

    fn errors(points: &[SurveyPoint], pairs: &[(usize, DVec3)], opts: &Options) -> Residuals {
        let a = align(points, pairs, opts).unwrap();
        residuals(points, pairs, &a.sim, opts, |_| 5)
    }

    #[test]
    fn a_check_point_is_held_out_of_the_alignment_and_a_control_point_is_not() {
        let (mut points, pairs) = block();
        let opts = split();
        let a = align(&points, &pairs, &opts).unwrap();
        assert_eq!((a.name, a.count), ("gcp", 4));
        let before = errors(&points, &pairs, &opts);
        let kinds: Vec<&str> = before.point_errors[..7].iter().map(|p| p.kind).collect();
        assert_eq!(
            kinds,
            ["gcp", "gcp", "gcp", "gcp", "check", "check", "check"]
        );
        assert_eq!((before.control.len(), before.check.len()), (4, 3));
        // The bowl shows at the held-out middle points, not at the fitted corners.
        let rms = |v: &[DVec3]| (v.iter().map(|e| e.z * e.z).sum::<f64>() / v.len() as f64).sqrt();
        assert!(
            rms(&before.check) > 3.0 * rms(&before.control),
            "check {} control {}",
            rms(&before.check),
            rms(&before.control)
        );
        // Move check point gcp_n0's truth up 0.5 m: its error drops by exactly 0.5 m, and no
        // other point's error changes (its truth did not enter the similarity).
        points[6].world.z += 0.5;
        let moved = errors(&points, &pairs, &opts);
        for (k, (b, m)) in before
            .point_errors
            .iter()
            .zip(&moved.point_errors)
            .enumerate()
        {
            let d = DVec3::from_array(m.error) - DVec3::from_array(b.error);
            let want = if k == 6 { -0.5 } else { 0.0 };
            assert!(
                (d - DVec3::Z * want).length() < 1e-12,
                "point {k} ({}) moved by {d}",
                b.label
            );
        }
        // Move control point gcp_w2's truth instead: the similarity follows it, and every
        // other point's error moves.
        points[6].world.z -= 0.5;
        points[0].world.z += 0.5;
        let moved = errors(&points, &pairs, &opts);
        for k in 1..points.len() {
            let d = DVec3::from_array(moved.point_errors[k].error)
                - DVec3::from_array(before.point_errors[k].error);
            assert!(
                d.length() > 1e-3,
                "point {k} did not follow the control point"
            );
        }
    }

    #[test]
    fn only_control_points_enter_the_adjustment_and_a_check_points_truth_never_does() {
        let (mut points, _) = block();
        let seen = vec![5u32; points.len()];
        let opts = split();
        let before = priors(&points, &seen, &opts, 0.002).unwrap();
        let ids: Vec<u64> = before.iter().map(|g| g.id).collect();
        assert_eq!(ids, [1, 2, 3, 4], "the four corner control points");
        assert!(before.iter().all(|g| g.sigma == 0.002));
        assert_eq!(before[0].xyz, points[0].world.to_array());
        // Move check point gcp_n0's truth: the adjustment's input does not change, so nothing
        // of the block can (only that point's own residual, measured against its truth).
        points[6].world.z += 0.5;
        assert_eq!(priors(&points, &seen, &opts, 0.002).unwrap(), before);
        // Move a control point's truth: the adjustment is told.
        points[0].world.z += 0.5;
        let moved = priors(&points, &seen, &opts, 0.002).unwrap();
        assert_eq!(moved[0].xyz[2], before[0].xyz[2] + 0.5);
        // A control point seen once is not reconstructed: with two left, a clear error.
        let mut seen_once = seen.clone();
        seen_once[0] = 1;
        seen_once[1] = 1;
        let e = priors(&points, &seen_once, &opts, 0.002).unwrap_err();
        assert!(
            e.contains("only 2 control point(s)") && e.contains("help:"),
            "{e}"
        );
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = priors(&points, &seen, &opts, bad).unwrap_err();
            assert!(e.contains("--gcp-sigma") && e.contains("help:"), "{e}");
        }
    }

    #[test]
    fn gcp_alone_makes_every_target_a_control_point_and_no_gcp_fits_on_all_points() {
        let (mut points, pairs) = block();
        let all = Options {
            gcp: true,
            ..Options::default()
        };
        let r = errors(&points, &pairs, &all);
        assert_eq!((r.control.len(), r.check.len()), (7, 0));
        let before = r.point_errors[0].error;
        points[6].world.z += 0.5;
        // gcp_n0 is a control point now: moving it moves the others.
        let after = errors(&points, &pairs, &all).point_errors[0].error;
        assert!((DVec3::from_array(after) - DVec3::from_array(before)).length() > 1e-3);
        let none = Options::default();
        let a = align(&points, &pairs, &none).unwrap();
        assert_eq!((a.name, a.count), ("all points", points.len()));
        let r = residuals(&points, &pairs, &a.sim, &none, |_| 0);
        assert_eq!((r.control.len(), r.check.len(), r.tie.len()), (0, 7, 40));
    }

    #[test]
    fn roles_follow_either_list_or_both() {
        let o = |control: &[&str], check: &[&str]| Options {
            gcp: true,
            control: control.iter().map(|s| s.to_string()).collect(),
            check: check.iter().map(|s| s.to_string()).collect(),
            ..Options::default()
        };
        let role = |l: &str, opts: &Options| target_role(l, opts);
        assert_eq!(role("a/1", &o(&[], &[])), Role::Control);
        assert_eq!(role("a/1", &o(&[], &["a"])), Role::Check);
        assert_eq!(role("b/2", &o(&[], &["a"])), Role::Control);
        assert_eq!(role("a/1", &o(&["a"], &[])), Role::Control);
        assert_eq!(role("b/2", &o(&["a"], &[])), Role::Check);
        assert_eq!(role("b/2", &o(&["a"], &["b/2"])), Role::Check);
        assert_eq!(role("c/3", &o(&["a"], &["b"])), Role::Unused);
        // A points file's id names its point.
        assert_eq!(role("gcps.csv/G7", &o(&["G7"], &[])), Role::Control);
        // A prefix of a name is not the name.
        assert_eq!(role("ab/1", &o(&["a"], &[])), Role::Check);
    }

    #[test]
    fn too_few_control_points_and_unknown_names_are_clear_errors() {
        let (points, pairs) = block();
        let two = Options {
            gcp: true,
            control: vec!["gcp_w2".into(), "gcp_e2".into()],
            ..Options::default()
        };
        let e = align(&points, &pairs, &two).unwrap_err();
        assert!(
            e.contains("only 2 control point(s)") && e.contains("help:"),
            "{e}"
        );
        let bad = Options {
            gcp: true,
            check: vec!["nosuch".into()],
            ..Options::default()
        };
        let e = align(&points, &pairs, &bad).unwrap_err();
        assert!(e.contains("--check: no target is named `nosuch`"), "{e}");
        let both = Options {
            gcp: true,
            control: vec!["gcp_w2".into()],
            check: vec!["gcp_w2/1".into()],
            ..Options::default()
        };
        let e = align(&points, &pairs, &both).unwrap_err();
        assert!(e.contains("both a control point"), "{e}");
    }
}
