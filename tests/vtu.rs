//! `solve --vtu`: the field file parses as VTK XML, has every node and
//! triangle of both bodies, arrays of the right lengths, and values that
//! agree with the run's own profile.csv.

use std::process::Command;

fn numbers(node: roxmltree::Node) -> Vec<f64> {
    node.text()
        .unwrap_or("")
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

#[test]
fn the_field_file_has_both_bodies_and_agrees_with_the_profile() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args([
            "solve",
            "--problem",
            "1",
            "--h",
            "1/16",
            "--solver",
            "newton-coulomb",
            "--vtu",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("field.vtu")).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    assert_eq!(
        doc.root_element().attribute("type"),
        Some("UnstructuredGrid")
    );
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    // 17 columns × 9 rows per body; 16 × 8 squares × 2 triangles per body.
    let (points, cells) = (17 * 9 * 2, 16 * 8 * 2 * 2);
    assert_eq!(
        piece.attribute("NumberOfPoints"),
        Some(points.to_string().as_str())
    );
    assert_eq!(
        piece.attribute("NumberOfCells"),
        Some(cells.to_string().as_str())
    );
    let array = |name: &str| {
        doc.descendants()
            .find(|n| n.has_tag_name("DataArray") && n.attribute("Name") == Some(name))
            .unwrap_or_else(|| panic!("no array {name}"))
    };
    for (name, count) in [
        ("coordinates", 3 * points),
        ("displacement", 3 * points),
        ("contact_state", points),
        ("contact_pressure", points),
        ("connectivity", 3 * cells),
        ("offsets", cells),
        ("types", cells),
        ("body", cells),
        ("stress", 3 * cells),
        ("von_mises", cells),
    ] {
        assert_eq!(numbers(array(name)).len(), count, "{name}");
    }
    // The stress's components are named, so ParaView shows σ11, σ22, σ12
    // rather than 0, 1, 2.
    let stress = array("stress");
    for (i, c) in ["sigma_11", "sigma_22", "sigma_12"].iter().enumerate() {
        assert_eq!(
            stress.attribute(format!("ComponentName{i}").as_str()),
            Some(*c)
        );
    }
    // The profile's first contact node (x = 0): the upper body's node on
    // Γ_K is node 17·9 (its row 0, column 0).
    let mut r = csv::Reader::from_path(out.join("profile.csv")).unwrap();
    let header = r.headers().unwrap().clone();
    let first = r.records().next().unwrap().unwrap();
    let col = |name: &str| {
        first[header.iter().position(|h| h == name).unwrap()]
            .parse::<f64>()
            .unwrap()
    };
    let u = numbers(array("displacement"));
    let upper0 = 17 * 9;
    assert!((u[3 * upper0 + 1] - col("u2_upper")).abs() <= 1e-9 * col("u2_upper").abs());
    assert!(
        (u[1] - 0.0).abs() < 1e-300,
        "the lower body is clamped at y = 0"
    );
    let p = numbers(array("contact_pressure"));
    assert!((p[upper0] - col("pressure")).abs() <= 1e-9 * col("pressure").abs());
    // Contact states: as many per body as the profile's rows, none elsewhere.
    let states = numbers(array("contact_state"));
    assert_eq!(states.iter().filter(|s| **s >= 0.0).count(), 2 * 17);
    assert!(
        numbers(array("von_mises"))
            .iter()
            .all(|v| *v >= 0.0 && v.is_finite())
    );
}
