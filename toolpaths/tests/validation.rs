//! Bad numbers are refused at the boundary with clear errors; unsafe programs are refused
//! with the amount of the violation.

mod common;

use common::{field_mesh, rect_mesh};
use grainline_toolpaths::*;

fn mesh() -> FieldMesh {
    field_mesh(rect_mesh(10.0, 5.0, 10, 5), Symmetry::Line, |_| [1.0, 0.0])
}

fn option_error(r: Result<JobOutput>, name: &str) {
    match r {
        Err(ToolpathError::InvalidOption { name: n, .. }) => assert_eq!(n, name),
        other => panic!("expected an invalid `{name}`, got {:?}", other.map(|o| o.report)),
    }
}

#[test]
fn zero_negative_or_nan_numbers_are_errors() {
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut o = JobOptions { gcode: Some(GcodeOptions::default()), ..Default::default() };
        o.placement.width = bad;
        option_error(generate(mesh(), &o), "placement.width");
        let mut o = JobOptions { gcode: Some(GcodeOptions::default()), ..Default::default() };
        o.gcode.as_mut().unwrap().feed = bad;
        option_error(generate(mesh(), &o), "gcode.feed");
        let mut o = JobOptions { gcode: Some(GcodeOptions::default()), ..Default::default() };
        o.gcode.as_mut().unwrap().plunge_feed = bad;
        option_error(generate(mesh(), &o), "gcode.plunge_feed");
        let mut o = JobOptions::default();
        o.placement.test_ratio = bad;
        option_error(generate(mesh(), &o), "placement.test_ratio");
        let mut o = JobOptions::default();
        o.plan.tolerance = bad;
        option_error(generate(mesh(), &o), "plan.tolerance");
    }
    // Overlap 1 would make the spacing zero.
    let mut o = JobOptions::default();
    o.placement.overlap = 1.0;
    option_error(generate(mesh(), &o), "placement.overlap");
    let msg = ToolpathError::InvalidOption {
        name: "gcode.feed",
        value: 0.0,
        reason: "must be finite and > 0",
    };
    assert_eq!(msg.to_string(), "gcode.feed: must be finite and > 0, got 0");
}

#[test]
fn bad_meshes_are_errors() {
    let mut m = mesh();
    m.uv[3][0] = f64::NAN;
    assert!(matches!(Domain::new(m), Err(ToolpathError::NonFinite { what: "uv", index: 3 })));
    let mut m = mesh();
    m.triangles[0] = [0, 1, 1000];
    assert!(matches!(Domain::new(m), Err(ToolpathError::InvalidMesh(_))));
    let mut m = mesh();
    m.uv[1] = m.uv[0];
    assert!(matches!(Domain::new(m), Err(ToolpathError::DegenerateTriangle { .. })));
    assert!(matches!(Symmetry::from_k(4), Err(ToolpathError::InvalidOption { .. })));
}

fn program(gcode: GcodeOptions) -> Result<JobOutput> {
    let o = JobOptions {
        placement: PlacementOptions::new(1.0, 0.0),
        plan: PlanOptions { contact_depth: 0.5, ..Default::default() },
        gcode: Some(gcode),
        ..Default::default()
    };
    generate(mesh(), &o)
}

#[test]
fn envelope_and_floor_violations_are_refused_with_the_amount() {
    // The rectangle spans X 0..10; an envelope ending at X = 9.25 is left by 0.75 mm.
    let env = Envelope { min: [-1.0, -1.0, -2.0], max: [9.25, 20.0, 10.0] };
    match program(GcodeOptions { envelope: Some(env), ..Default::default() }) {
        Err(e @ ToolpathError::OutsideEnvelope { axis: 'X', .. }) => {
            let ToolpathError::OutsideEnvelope { by, .. } = e else { unreachable!() };
            assert!(by > 0.0 && by <= 0.75 + 1e-9, "by {by}");
            assert!(e.to_string().contains("by"), "{e}");
        }
        other => panic!("expected an envelope error, got {:?}", other.map(|o| o.report)),
    }
    // Safe Z above the envelope top is refused too.
    let env = Envelope { min: [-1.0, -1.0, -2.0], max: [20.0, 20.0, 3.0] };
    assert!(matches!(
        program(GcodeOptions { envelope: Some(env), safe_z: 5.0, ..Default::default() }),
        Err(ToolpathError::OutsideEnvelope { axis: 'Z', .. })
    ));
    // Cutting at Z = −0.5 with the floor at −0.2: refused by 0.3 mm.
    match program(GcodeOptions { z_floor: Some(-0.2), ..Default::default() }) {
        Err(e @ ToolpathError::BelowFloor { .. }) => {
            assert!(e.to_string().contains("by 0.3 mm"), "{e}");
        }
        other => panic!("expected a floor error, got {:?}", other.map(|o| o.report)),
    }
    // Within limits: accepted.
    let env = Envelope { min: [-1.0, -1.0, -1.0], max: [11.0, 6.0, 6.0] };
    assert!(program(GcodeOptions {
        envelope: Some(env),
        z_floor: Some(-0.5),
        ..Default::default()
    })
    .is_ok());
}

#[test]
fn every_section_names_its_key_path() {
    let m = || mesh();
    let mut o = JobOptions::default();
    o.placement.trace.max_step = -1.0;
    option_error(generate(m(), &o), "placement.trace.max_step");
    let o = JobOptions {
        coverage: Some(CoverageOptions { resolution: Some(0.0), ..Default::default() }),
        ..Default::default()
    };
    option_error(generate(m(), &o), "coverage.resolution");
    let o = JobOptions {
        svg: Some(SvgOptions { decimals: 9, ..Default::default() }),
        ..Default::default()
    };
    option_error(generate(m(), &o), "svg.decimals");
    let mut o = JobOptions::default();
    o.plan.z_mode = ZMode::SurfaceFollowing { max_tilt_deg: 200.0, on_tilt: TiltPolicy::Skip };
    option_error(generate(m(), &o), "plan.z_mode.max_tilt_deg");
    let mut o = JobOptions { gcode: Some(GcodeOptions::default()), ..Default::default() };
    o.gcode.as_mut().unwrap().spindle = Spindle::Speed(-5.0);
    option_error(generate(m(), &o), "gcode.spindle.speed");
}

#[test]
fn unknown_keys_are_refused_at_every_level() {
    let ok: JobOptions = serde_json::from_str(
        r#"{"placement": {"width": 2.0, "trace": {"cross_seams": true}},
            "plan": {"z_mode": {"mode": "flat", "surface_z": 1.0}, "order": {"home": [1, 2]}},
            "gcode": {"spindle": {"speed": 900}, "envelope": {"min": [0,0,0], "max": [1,1,1]}},
            "svg": {}, "coverage": {}}"#,
    )
    .unwrap();
    assert_eq!(ok.placement.width, 2.0);
    assert!(ok.placement.trace.cross_seams);
    assert_eq!(ok.plan.z_mode, ZMode::Flat { surface_z: 1.0 });
    for bad in [
        r#"{"placement": {"widht": 2.0}}"#,
        r#"{"placement": {"trace": {"tolerence": 1}}}"#,
        r#"{"plan": {"order": {"homes": [0, 0]}}}"#,
        r#"{"plan": {"z_mode": {"mode": "flat", "surface_z": 0, "extra": 1}}}"#,
        r#"{"gcode": {"envelope": {"min": [0,0,0], "max": [1,1,1], "mid": 0}}}"#,
        r#"{"gcode": {"spindle": {"snippet": {"on": "M7", "off": "M9", "x": 1}}}}"#,
        r#"{"svg": {"margins": 1}}"#,
        r#"{"coverage": {"resolutoin": 1}}"#,
        r#"{"strokes": true}"#,
    ] {
        let e = serde_json::from_str::<JobOptions>(bad).expect_err(bad).to_string();
        assert!(e.contains("unknown field"), "{bad}: {e}");
    }
}
