//! STL and PLY: what each reads, the binary/ASCII decision, and errors that name file and line,
//! facet or element.

use glam::Vec3;
use shadowvol_mesh_topology::EdgeTable;
use shadowvol_scenes::ply::parse_ply;
use shadowvol_scenes::stl::parse_stl;

fn binary_stl(header: &[u8], facets: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = vec![b' '; 80];
    out[..header.len()].copy_from_slice(header);
    out.extend_from_slice(&(facets.len() as u32).to_le_bytes());
    for f in facets {
        out.extend_from_slice(&[0u8; 12]); // normal, ignored
        for v in f {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

/// `facets` as ASCII STL, two solids, lines ending in `eol`, coordinates written exactly.
fn ascii_stl(facets: &[[[f32; 3]; 3]], eol: &str) -> Vec<u8> {
    let mut text = format!("solid first{eol}");
    for (k, f) in facets.iter().enumerate() {
        if k == facets.len() / 2 {
            text.push_str(&format!("endsolid first{eol}solid second{eol}"));
        }
        text.push_str(&format!("facet normal 0 0 1{eol} outer loop{eol}"));
        for v in f {
            text.push_str(&format!("  vertex {:?} {:?} {:?}{eol}", v[0], v[1], v[2]));
        }
        text.push_str(&format!(" endloop{eol}endfacet{eol}"));
    }
    text.push_str(&format!("endsolid second{eol}"));
    text.into_bytes()
}

const TETRA: [[[f32; 3]; 3]; 4] = [
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
];

#[test]
fn binary_stl_is_a_soup_that_welds_into_a_closed_mesh_even_with_a_solid_header() {
    let bytes = binary_stl(b"solid exported by a CAD tool", &TETRA);
    let mesh = parse_stl(&bytes, "t.stl").unwrap();
    assert_eq!(mesh.positions.len(), 12);
    assert_eq!(mesh.triangles[3], [9, 10, 11]);
    assert_eq!(mesh.positions[10], Vec3::new(0.0, 1.0, 0.0));
    let table = EdgeTable::build(&mesh).unwrap();
    assert_eq!(table.stats.welded_vertices, 4);
    assert_eq!(table.stats.edges, 6);
    assert_eq!(table.stats.boundary_edges, 0);
}

#[test]
fn ascii_stl_reads_the_same_mesh_with_any_case_and_several_solids() {
    let mut text = String::from("  solid  first part\n");
    for (k, f) in TETRA.iter().enumerate() {
        if k == 2 {
            text.push_str("endsolid first part\nSOLID second\n");
        }
        text.push_str("  facet normal nan nan nan\n    outer loop\n");
        for v in f {
            text.push_str(&format!("      VERTEX {:e} {} {}\n", v[0], v[1], v[2]));
        }
        text.push_str("    endloop\n  endfacet\n");
    }
    text.push_str("endsolid second\n");
    let ascii = parse_stl(text.as_bytes(), "a.stl").unwrap();
    let binary = parse_stl(&binary_stl(b"", &TETRA), "b.stl").unwrap();
    assert_eq!(ascii, binary);
    // An empty solid has no triangles (the CLI then says so).
    assert!(parse_stl(b"solid empty\nendsolid empty\n", "e.stl")
        .unwrap()
        .triangles
        .is_empty());
}

#[test]
fn stl_errors_name_file_and_line_or_facet() {
    let e = |b: &[u8]| parse_stl(b, "bad.stl").unwrap_err().to_string();
    let m = e(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n");
    assert_eq!(m, "bad.stl: line 6: expected \"vertex\", found 'endloop'");
    let m = e(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 inf 0\n");
    assert_eq!(
        m,
        "bad.stl: line 4: vertex coordinate y is inf, but positions must be finite"
    );
    let m = e(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n");
    // The end of the file is after the last newline: line 9.
    assert_eq!(
        m,
        "bad.stl: line 9: end of file inside a solid: \"endsolid\" expected"
    );
    let m = e(b"solid x\nfacade\n");
    assert_eq!(
        m,
        "bad.stl: line 2: expected \"facet\" or \"endsolid\", found 'facade'"
    );
    let m = e(b"PK\x03\x04 not an stl");
    assert!(
        m.starts_with("bad.stl: header: 15 bytes: too short for a binary STL"),
        "{m}"
    );
    // Binary: a length that does not match the facet count, and a NaN corner.
    let mut b = binary_stl(b"", &TETRA);
    b.push(0);
    let m = e(&b);
    assert!(
        m.contains("declares 4 facets, 84 + 50 * 4 = 284 bytes, but the file has 285"),
        "{m}"
    );
    let mut f = TETRA;
    f[2][1][2] = f32::NAN;
    let m = e(&binary_stl(b"", &f));
    assert_eq!(m, format!("bad.stl: facet 2 (byte {}): vertex 1 coordinate z is NaN, but positions must be finite", 84 + 100 + 12 + 12 + 8));
}

fn ply_header(
    format: &str,
    vertex_props: &str,
    faces: usize,
    face_props: &str,
    vertices: usize,
) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment made by hand\nelement vertex {vertices}\n{vertex_props}\
         element face {faces}\n{face_props}end_header\n"
    )
}

#[test]
fn ply_reads_positions_and_fans_polygons_ignoring_other_properties() {
    // A pentagon and a triangle; colours, normals and a face property are ignored.
    let vp = "property float x\nproperty float y\nproperty float z\nproperty float nx\n\
              property uchar red\n";
    let fp = "property uchar flags\nproperty list uchar int vertex_indices\nproperty float q\n";
    let mut text = ply_header("ascii", vp, 2, fp, 6);
    text.push_str("0 0 0 1 255\n1 0 0 1 255\n2 1 0 1 255\n1 2 0 1 255\n0 1 0 1 255\n5 5 5 0 0\n");
    text.push_str("7 5 0 1 2 3 4 0.5\n0 3 0 4 5 1.5\n");
    let mesh = parse_ply(text.as_bytes(), "p.ply").unwrap();
    assert_eq!(mesh.positions.len(), 6);
    assert_eq!(mesh.positions[2], Vec3::new(2.0, 1.0, 0.0));
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);

    // The same in binary big-endian, with double coordinates and ushort/uint lists.
    let vp = "property double x\nproperty double y\nproperty double z\nproperty uchar red\n";
    let fp = "property list uchar uint vertex_indices\n";
    let mut bin = ply_header("binary_big_endian", vp, 2, fp, 6).into_bytes();
    for p in &mesh.positions {
        for c in p.to_array() {
            bin.extend_from_slice(&f64::from(c).to_be_bytes());
        }
        bin.push(7);
    }
    for face in [&[0u32, 1, 2, 3, 4][..], &[0, 4, 5]] {
        bin.push(face.len() as u8);
        for i in face {
            bin.extend_from_slice(&i.to_be_bytes());
        }
    }
    assert_eq!(parse_ply(&bin, "be.ply").unwrap(), mesh);
    // Little-endian, with elements before and after the mesh's (read and dropped), from a
    // file read a buffer at a time.
    let vp = "property float x\nproperty float y\nproperty float z\n";
    let mut le = "ply\nformat binary_little_endian 1.0\nelement material 2\nproperty uchar id\n\
                  property list uchar float rgb\nelement vertex 6\n"
        .to_owned();
    le.push_str(vp);
    le.push_str(
        "element face 2\nproperty list uchar int vertex_indices\nelement edge 1\n\
                 property int vertex1\nproperty int vertex2\nend_header\n",
    );
    let mut le = le.into_bytes();
    for id in [1u8, 2] {
        le.push(id);
        le.push(3);
        for c in [0.5f32, 0.25, 1.0] {
            le.extend_from_slice(&c.to_le_bytes());
        }
    }
    for p in &mesh.positions {
        for c in p.to_array() {
            le.extend_from_slice(&c.to_le_bytes());
        }
    }
    for face in [&[0i32, 1, 2, 3, 4][..], &[0, 4, 5]] {
        le.push(face.len() as u8);
        for i in face {
            le.extend_from_slice(&i.to_le_bytes());
        }
    }
    for v in [0i32, 5] {
        le.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(parse_ply(&le, "le.ply").unwrap(), mesh);
    let path = std::env::temp_dir().join(format!("shadowvol-le-{}.ply", std::process::id()));
    std::fs::write(&path, &le).unwrap();
    assert_eq!(shadowvol_scenes::ply::load_ply(&path).unwrap(), mesh);
    std::fs::remove_file(&path).unwrap();
    // A point cloud (no face element) has no triangles.
    let cloud = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n1 2 3\n";
    assert!(parse_ply(cloud.as_bytes(), "c.ply")
        .unwrap()
        .triangles
        .is_empty());
}

#[test]
fn ply_errors_name_file_and_element_or_line() {
    let vp = "property float x\nproperty float y\nproperty float z\n";
    let fp = "property list uchar int vertex_indices\n";
    let e = |body: &str, faces: usize| {
        let text = ply_header("ascii", vp, faces, fp, 3) + body;
        parse_ply(text.as_bytes(), "bad.ply")
            .unwrap_err()
            .to_string()
    };
    let m = e("0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 1);
    assert_eq!(m, "bad.ply: element face 0: corner 2: vertex index 3 is out of range (the file has 3 vertices)");
    let m = e("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 -1 2\n", 2);
    assert_eq!(
        m,
        "bad.ply: element face 1: corner 1: vertex index -1 is negative"
    );
    let m = e("0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 1);
    assert_eq!(
        m,
        "bad.ply: element face 0: face has 2 corner(s), but at least 3 are needed"
    );
    let mut bin = ply_header("binary_little_endian", vp, 1, fp, 3).into_bytes();
    for c in [0.0f32, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    bin.extend_from_slice(&[3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    let m = parse_ply(&bin, "bad.ply").unwrap_err().to_string();
    assert_eq!(
        m,
        "bad.ply: element vertex 1: coordinate y is NaN, but positions must be finite"
    );
    let m = e("0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", 1);
    // The header has 10 lines: the second vertex is line 12.
    assert!(m.starts_with("bad.ply: line 12: "), "{m}");
    let m = e("0 0 0\n1 0 0\n", 1);
    assert!(
        m.starts_with("bad.ply: line ") && m.contains("end of file"),
        "{m}"
    );
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                end_header\n1 2\n";
    let m = parse_ply(text.as_bytes(), "bad.ply")
        .unwrap_err()
        .to_string();
    assert_eq!(
        m,
        "bad.ply: header: the vertex element has no \"z\" property"
    );
    let m = parse_ply(b"plx\nformat ascii 1.0\n", "bad.ply")
        .unwrap_err()
        .to_string();
    assert!(m.starts_with("bad.ply: line 1: "), "{m}");
    // Binary data that ends early.
    let mut bin = ply_header("binary_little_endian", vp, 1, fp, 3).into_bytes();
    bin.extend_from_slice(&[0u8; 20]);
    let m = parse_ply(&bin, "bad.ply").unwrap_err().to_string();
    assert!(m.starts_with("bad.ply: "), "{m}");
}

/// A binary file is welded as it is read: the table equals the one built from the soup
/// `load_stl` gives (names, sources, degenerate facets, -0.0), on files of every kind, and the
/// errors are those of `load_stl`.
#[test]
fn stl_tables_welded_as_read_equal_the_soup_build() {
    let dir = std::env::temp_dir().join(format!("shadowvol-stl-table-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    // A tetrahedron with -0.0 corners, a facet degenerate after welding, and a fan of 300
    // facets (enough distinct corners to grow the weld's index table).
    let mut facets = TETRA.to_vec();
    facets[1][0] = [-0.0, 0.0, -0.0];
    facets.push([[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    for i in 0..300 {
        let a = i as f32 * 0.01;
        facets.push([
            [5.0, 0.0, 0.0],
            [5.0 + a, 1.0, 0.0],
            [5.0 + a + 0.01, 1.0, 0.0],
        ]);
    }
    let ascii = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
        vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    for (name, bytes) in [
        ("tetra.stl", binary_stl(b"solid exported", &TETRA)),
        ("mixed.stl", binary_stl(b"", &facets)),
        ("ascii.stl", ascii.to_vec()),
        ("mixed-ascii.stl", ascii_stl(&facets, "\n")),
        ("mixed-crlf.stl", ascii_stl(&facets, "\r\n")),
    ] {
        let path = write(name, &bytes);
        let soup = shadowvol_scenes::stl::load_stl(&path).unwrap();
        let want = EdgeTable::build(&soup).unwrap();
        let got = shadowvol_scenes::stl::load_stl_table(&path).unwrap();
        assert_eq!(got, want, "{name}");
    }
    let mut f = TETRA;
    f[2][1][2] = f32::NAN;
    let mut bad = ascii_stl(&TETRA, "\n");
    bad.truncate(bad.len() - 40);
    for (name, bytes) in [
        ("nan.stl", binary_stl(b"", &f)),
        ("short.stl", b"PK\x03\x04 not an stl".to_vec()),
        ("nan-ascii.stl", ascii_stl(&f, "\r\n")),
        ("cut-ascii.stl", bad),
        (
            "word-ascii.stl",
            b"solid a\nfacet normal 0 0 1\nouter lop\n".to_vec(),
        ),
    ] {
        let path = write(name, &bytes);
        let want = shadowvol_scenes::stl::load_stl(&path)
            .unwrap_err()
            .to_string();
        let got = shadowvol_scenes::stl::load_stl_table(&path)
            .unwrap_err()
            .to_string();
        assert_eq!(got, want, "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
