//! Mesh loaders and writers: every format on small files, write→read round
//! trips, each error kind, and a no-panic mutation test.

use std::path::{Path, PathBuf};

use cbvh::mesh::{Format, Mesh, MeshError, Place, load, load_bytes, save};
use proptest::prelude::*;

/// A fresh directory under the system temp dir for one test.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cbvh-mesh-io-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes `bytes` to `name` in the test's temp dir and loads it.
fn load_file(test: &str, name: &str, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let dir = temp_dir(test);
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let result = load(&path);
    let _ = std::fs::remove_dir_all(dir);
    result
}

/// Vertices shared by the sample files: a unit square and an apex.
const VERTS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.5, 1.5],
];
/// The quad 0 1 2 3 fan-triangulated, then the triangle 1 4 2.
const TRIS: [[u32; 3]; 3] = [[0, 1, 2], [0, 2, 3], [1, 4, 2]];

fn sample() -> Mesh {
    Mesh::new(VERTS.to_vec(), TRIS.to_vec())
}

const OFF: &str = "OFF
# a square and a triangle
5 2 0

0 0 0
1 0 0 255 0 0
1 1 0
0 1 0   # trailing comment
0.5 0.5 1.5
4 0 1 2 3
3 1 4 2 0.1 0.2 0.3
";

const PLY_ASCII: &str = "ply
format ascii 1.0
comment a square and a triangle
element vertex 5
property float x
property float y
property float z
property uchar red
element edge 1
property int vertex1
property int vertex2
element face 2
property list uchar int vertex_indices
property list uchar float texcoord
end_header
0 0 0 1
1 0 0 2
1 1 0 3
0 1 0 4
0.5 0.5 1.5 5
0 1
4 0 1 2 3 2 0.5 0.5
3 1 4 2 0
";

const OBJ: &str = "# a square and a triangle
mtllib none.mtl
o first
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0 1.0
vt 0 0
vn 0 0 1
usemtl none
s off
f 1/1/1 2/1/1 3/1/1 4/1/1
g second
v 0.5 0.5 \\
  1.5
f -4//1 -1//1 -3//1
l 1 2
";

/// Binary PLY of the sample: doubles and an ignored normal for vertices,
/// `ushort` counts and `uint` indices for faces, plus an ignored element.
fn ply_binary(big: bool) -> Vec<u8> {
    let enc = if big {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {enc} 1.0\nelement vertex 5\nproperty double x\nproperty double y\n\
         property double z\nproperty float nx\nelement face 2\n\
         property list ushort uint vertex_indices\nelement extra 1\n\
         property list uchar short junk\nend_header\n"
    )
    .into_bytes();
    let put = |out: &mut Vec<u8>, le: &[u8], be: &[u8]| {
        out.extend_from_slice(if big { be } else { le });
    };
    for v in VERTS {
        for c in v {
            let c = f64::from(c);
            put(&mut out, &c.to_le_bytes(), &c.to_be_bytes());
        }
        put(&mut out, &7f32.to_le_bytes(), &7f32.to_be_bytes());
    }
    for face in [&[0u32, 1, 2, 3][..], &[1, 4, 2]] {
        let n = face.len() as u16;
        put(&mut out, &n.to_le_bytes(), &n.to_be_bytes());
        for &i in face {
            put(&mut out, &i.to_le_bytes(), &i.to_be_bytes());
        }
    }
    out.push(2);
    put(&mut out, &5i16.to_le_bytes(), &5i16.to_be_bytes());
    put(&mut out, &(-5i16).to_le_bytes(), &(-5i16).to_be_bytes());
    out
}

/// Where a binary PLY's data starts: just after its `end_header` line.
fn body_start(ply: &[u8]) -> usize {
    ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11
}

/// Two triangles of the unit square sharing the diagonal; one corner is
/// written as -0 to check that it still welds with 0.
const STL_ASCII: &str = "solid square
facet normal 0 0 1
  outer loop
    vertex 0 0 0
    vertex 1 0 0
    vertex 1 1 0
  endloop
endfacet
facet normal 0 0 1
  outer loop
    vertex -0 0 0
    vertex 1 1 0
    vertex 0 1 0
  endloop
endfacet
endsolid square
";

/// The same two triangles as binary STL, with a header that starts with
/// "solid" as many exporters write it.
fn stl_binary() -> Vec<u8> {
    let mut out = b"solid but actually binary".to_vec();
    out.resize(80, b' ');
    out.extend_from_slice(&2u32.to_le_bytes());
    let tris = [
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
        [[-0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ];
    for t in tris {
        for c in [0.0f32, 0.0, 1.0] {
            out.extend_from_slice(&c.to_le_bytes());
        }
        for v in t {
            for c in v {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

fn assert_sample(mesh: &Mesh) {
    assert_eq!(mesh.vertices, VERTS.to_vec());
    assert_eq!(mesh.triangles, TRIS.to_vec());
}

fn assert_square(mesh: &Mesh) {
    let expected = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    assert_eq!(mesh.vertices, expected.to_vec());
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn loads_off() {
    assert_sample(&load_file("off", "a.off", OFF.as_bytes()).unwrap());
    // Variants: counts on the header line, COFF keyword, no keyword, CRLF.
    let inline = OFF.replacen("OFF\n# a square and a triangle\n5 2 0", "OFF 5 2 0", 1);
    assert_sample(&load_bytes(inline.as_bytes(), Format::Off, Path::new("i.off")).unwrap());
    let coff = OFF.replacen("OFF", "COFF", 1);
    assert_sample(&load_bytes(coff.as_bytes(), Format::Off, Path::new("c.off")).unwrap());
    let bare = OFF.replacen("OFF\n", "", 1);
    assert_sample(&load_bytes(bare.as_bytes(), Format::Off, Path::new("b.off")).unwrap());
    let crlf = OFF.replace('\n', "\r\n");
    assert_sample(&load_bytes(crlf.as_bytes(), Format::Off, Path::new("r.off")).unwrap());
}

#[test]
fn loads_ply_ascii() {
    assert_sample(&load_file("ply-ascii", "a.PLY", PLY_ASCII.as_bytes()).unwrap());
}

/// A Blender export had a header line without the `comment` keyword
/// ("Created by Blender ..."); assimp reads it, so cbvh skips it with a
/// warning instead of rejecting the file.
#[test]
fn ply_header_line_without_keyword_is_skipped() {
    let blender = PLY_ASCII.replace(
        "comment a square and a triangle\n",
        "Created by Blender 3.6.0 - www.blender.org\n",
    );
    assert!(blender.contains("Created by"));
    assert_sample(&load_bytes(blender.as_bytes(), Format::Ply, Path::new("b.ply")).unwrap());
}

#[test]
fn loads_ply_binary_both_endians() {
    assert_sample(&load_file("ply-le", "le.ply", &ply_binary(false)).unwrap());
    assert_sample(&load_file("ply-be", "be.ply", &ply_binary(true)).unwrap());
}

#[test]
fn loads_obj() {
    // Groups share the global vertex list; negative indices are relative.
    assert_sample(&load_file("obj", "a.obj", OBJ.as_bytes()).unwrap());
}

#[test]
fn loads_stl_ascii_and_binary_welded() {
    let ascii = load_file("stl-ascii", "a.stl", STL_ASCII.as_bytes()).unwrap();
    assert_square(&ascii);
    let binary = load_file("stl-binary", "b.Stl", &stl_binary()).unwrap();
    assert_square(&binary);
}

#[test]
fn degenerate_triangles_are_kept() {
    let off = "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 0 1\n";
    let mesh = load_bytes(off.as_bytes(), Format::Off, Path::new("d.off")).unwrap();
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 0, 1]]);
}

/// A mesh with awkward coordinates for exact round trips.
fn tricky() -> Mesh {
    let vertices = vec![
        [0.1, -0.0, 1.0 / 3.0],
        [1e-30, 3.4e38, -f32::MIN_POSITIVE],
        [1e-45, -123456.79, 16777217.0],
        [f32::MAX, f32::MIN, f32::EPSILON],
    ];
    Mesh::new(vertices, vec![[0, 1, 2], [3, 2, 1], [0, 0, 3]])
}

fn bits(mesh: &Mesh) -> Vec<[u32; 3]> {
    mesh.vertices.iter().map(|v| v.map(f32::to_bits)).collect()
}

#[test]
fn ply_and_obj_round_trips_are_exact() {
    let dir = temp_dir("round-trip");
    for mesh in [sample(), tricky()] {
        for name in ["m.ply", "m.obj", "M.OBJ"] {
            let path = dir.join(name);
            save(&mesh, &path).unwrap();
            let back = load(&path).unwrap();
            assert_eq!(bits(&back), bits(&mesh), "{name}");
            assert_eq!(back.triangles, mesh.triangles, "{name}");
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

fn off_err(text: &str) -> MeshError {
    load_bytes(text.as_bytes(), Format::Off, Path::new("bad.off")).unwrap_err()
}

#[test]
fn unknown_and_unwritable_extensions() {
    let err = load("/nonexistent/mesh.xyz").unwrap_err();
    assert!(
        matches!(&err, MeshError::UnknownExtension { ext, .. } if ext == "xyz"),
        "{err}"
    );
    assert!(err.to_string().contains(".off"), "{err}");
    let err = load("/nonexistent/mesh").unwrap_err();
    assert!(matches!(err, MeshError::UnknownExtension { .. }), "{err}");
    let dir = temp_dir("unwritable");
    for name in ["m.stl", "m.off", "m.txt"] {
        let err = save(&sample(), dir.join(name)).unwrap_err();
        assert!(matches!(err, MeshError::UnsupportedWrite { .. }), "{err}");
        assert!(err.to_string().contains("only .ply and .obj"), "{err}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn missing_file_is_io_error() {
    let err = load("/nonexistent/dir/mesh.off").unwrap_err();
    assert!(matches!(err, MeshError::Io(_)), "{err}");
    assert!(err.to_string().contains("mesh.off"), "{err}");
}

#[test]
fn truncated_off() {
    // Cut after the third vertex line: the fourth vertex (index 3) is missing.
    let cut: String = OFF.lines().take(7).map(|l| format!("{l}\n")).collect();
    let err = off_err(&cut);
    assert!(
        matches!(
            &err,
            MeshError::Truncated {
                place: Place::Line(8),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("vertex 3 of 5"), "{err}");
    // Cut inside a face line.
    let end = OFF.find("3 1 4").unwrap() + 4;
    let err = off_err(&OFF[..end]);
    assert!(
        matches!(
            err,
            MeshError::Truncated {
                place: Place::Line(11),
                ..
            }
        ),
        "{err:?}"
    );
    // Cut inside the header.
    assert!(matches!(off_err(""), MeshError::Truncated { .. }));
    assert!(matches!(off_err("OFF\n"), MeshError::Truncated { .. }));
}

#[test]
fn truncated_binary_ply() {
    let bytes = ply_binary(false);
    let cut = &bytes[..bytes.len() - 7];
    let err = load_bytes(cut, Format::Ply, Path::new("cut.ply")).unwrap_err();
    match &err {
        MeshError::Truncated { place, .. } => assert_eq!(*place, Place::Byte(cut.len() as u64)),
        _ => panic!("{err:?}"),
    }
    assert!(
        err.to_string()
            .contains(&format!("byte offset {}", cut.len())),
        "{err}"
    );
    // Cut inside the header.
    let err = load_bytes(&bytes[..30], Format::Ply, Path::new("cut.ply")).unwrap_err();
    assert!(err.to_string().contains("end_header"), "{err}");
}

#[test]
fn binary_stl_with_data_beyond_its_count_is_an_error() {
    let mut bytes = stl_binary();
    bytes[80..84].copy_from_slice(&1u32.to_le_bytes());
    let err = load_bytes(&bytes, Format::Stl, Path::new("short.stl")).unwrap_err();
    assert!(
        matches!(
            &err,
            MeshError::Malformed {
                place: Place::Byte(134),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("counts 1 triangle(s)"), "{err}");
    // The file as written, with its count right, still loads.
    assert_eq!(
        load_bytes(&stl_binary(), Format::Stl, Path::new("ok.stl"))
            .unwrap()
            .triangle_count(),
        2
    );
}

/// Issue 51: a header whose counts disagree with the body is refused in
/// both directions, naming the counts. A count short of the body used to
/// load the records it counts and drop the rest without a word (OFF, PLY);
/// binary STL refused it already.
#[test]
fn header_counts_that_disagree_with_the_body_are_refused() {
    let load = |bytes: &[u8], format: Format| load_bytes(bytes, format, Path::new("n.x"));
    // OFF: the counts are on line 3, "5 2 0".
    for (counts, place, want) in [
        (
            "5 1 0",
            Place::Line(11),
            "5 vertices and 1 faces that the counts on line 3",
        ),
        (
            "4 2 0",
            Place::Line(9),
            "the counts on line 3 announce 4 vertices",
        ),
    ] {
        let err = load(OFF.replacen("5 2 0", counts, 1).as_bytes(), Format::Off).unwrap_err();
        assert!(
            matches!(&err, MeshError::Malformed { place: p, .. } if *p == place),
            "{counts}: {err:?}"
        );
        assert!(err.to_string().contains(want), "{counts}: {err}");
    }
    for counts in ["5 3 0", "6 2 0"] {
        let err = load(OFF.replacen("5 2 0", counts, 1).as_bytes(), Format::Off).unwrap_err();
        assert!(
            matches!(err, MeshError::Truncated { .. }),
            "{counts}: {err:?}"
        );
    }
    // Trailing comments and blank lines are no data.
    let commented = format!("{OFF}\n# the end\n\n");
    assert_sample(&load(commented.as_bytes(), Format::Off).unwrap());
    // ASCII PLY: vertex 5 on line 4, edge 1 on line 9, face 2 on line 12.
    let err = load(
        PLY_ASCII
            .replacen("element face 2", "element face 1", 1)
            .as_bytes(),
        Format::Ply,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::Malformed {
                place: Place::Line(23),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("face 1 on line 12") && err.to_string().contains("count is short"),
        "{err}"
    );
    for (from, to) in [
        ("element face 2", "element face 3"),
        ("element vertex 5", "element vertex 4"),
        ("element vertex 5", "element vertex 6"),
    ] {
        let text = PLY_ASCII.replacen(from, to, 1);
        assert!(load(text.as_bytes(), Format::Ply).is_err(), "{to}");
    }
    let blank_end = format!("{PLY_ASCII}\n  \n");
    assert_sample(&load(blank_end.as_bytes(), Format::Ply).unwrap());
    // Binary PLY: a face count short of the faces (the second face's bytes
    // are then read as the extra element and some are left over), and a
    // byte after the last record.
    for big in [false, true] {
        let bytes = ply_binary(big);
        let at = bytes
            .windows(14)
            .position(|w| w == b"element face 2")
            .unwrap();
        let mut short = bytes.clone();
        short[at + 13] = b'1';
        let mut longer = bytes.clone();
        longer.push(0);
        for (what, b) in [("face 1", &short), ("a byte after", &longer)] {
            let err = load(b, Format::Ply).unwrap_err();
            assert!(
                matches!(
                    err,
                    MeshError::Malformed {
                        place: Place::Byte(_),
                        ..
                    }
                ) && err.to_string().contains("count is short"),
                "{what} (big-endian {big}): {err:?}"
            );
        }
        let mut more = bytes.clone();
        more[at + 13] = b'3';
        assert!(
            load(&more, Format::Ply).is_err(),
            "face 3 (big-endian {big})"
        );
    }
    // Binary STL, both directions.
    for (count, truncated) in [(1u32, false), (3, true)] {
        let mut bytes = stl_binary();
        bytes[80..84].copy_from_slice(&count.to_le_bytes());
        let err = load(&bytes, Format::Stl).unwrap_err();
        assert_eq!(
            matches!(err, MeshError::Truncated { .. }),
            truncated,
            "{count}: {err:?}"
        );
    }
}

#[test]
fn truncated_binary_stl() {
    let bytes = stl_binary();
    let cut = &bytes[..bytes.len() - 10];
    let err = load_bytes(cut, Format::Stl, Path::new("cut.stl")).unwrap_err();
    assert!(
        matches!(&err, MeshError::Truncated { place: Place::Byte(b), .. } if *b == cut.len() as u64),
        "{err:?}"
    );
    assert!(err.to_string().contains("triangle 1 of 2"), "{err}");
    // Cut inside the header (a header of text starting with "solid" would
    // make such a short file look like ASCII STL).
    let mut bytes = bytes;
    bytes[..6].copy_from_slice(b"binary");
    let err = load_bytes(&bytes[..50], Format::Stl, Path::new("cut.stl")).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::Truncated {
                place: Place::Byte(50),
                ..
            }
        ),
        "{err:?}"
    );
    // ASCII STL without endsolid.
    let cut = STL_ASCII.replace("endsolid square\n", "");
    let err = load_bytes(cut.as_bytes(), Format::Stl, Path::new("cut.stl")).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::Truncated {
                place: Place::Line(16),
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn index_out_of_range_names_face_index_and_count() {
    let bad = OFF.replace("3 1 4 2", "3 1 7 2");
    let err = off_err(&bad);
    assert!(
        matches!(
            err,
            MeshError::IndexOutOfRange {
                face: 1,
                index: 7,
                vertices: 5,
                place: Place::Line(11),
                ..
            }
        ),
        "{err:?}"
    );
    let msg = err.to_string();
    for part in ["bad.off", "line 11", "face 1", "index 7", "only 5 vertices"] {
        assert!(msg.contains(part), "{msg} lacks {part}");
    }

    let bad = PLY_ASCII.replace("3 1 4 2", "3 1 5 2");
    let err = load_bytes(bad.as_bytes(), Format::Ply, Path::new("bad.ply")).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::IndexOutOfRange {
                face: 1,
                index: 5,
                vertices: 5,
                place: Place::Line(23),
                ..
            }
        ),
        "{err:?}"
    );

    // Binary: the face record's byte offset is reported.
    let mut bytes = ply_binary(false);
    let header = body_start(&bytes);
    let face1 = header + 5 * 28 + 2 + 4 * 4;
    bytes[face1 + 2 + 4..face1 + 2 + 8].copy_from_slice(&99u32.to_le_bytes());
    let err = load_bytes(&bytes, Format::Ply, Path::new("bad.ply")).unwrap_err();
    assert!(
        matches!(err, MeshError::IndexOutOfRange { face: 1, index: 99, place: Place::Byte(b), .. } if b == face1 as u64),
        "{err:?}"
    );

    // OBJ: forward references are allowed, but must exist in the end.
    let bad = OBJ.replace("f -4//1 -1//1 -3//1", "f 2 6 3");
    let err = load_bytes(bad.as_bytes(), Format::Obj, Path::new("bad.obj")).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::IndexOutOfRange {
                face: 1,
                index: 6,
                vertices: 5,
                place: Place::Line(16),
                ..
            }
        ),
        "{err:?}"
    );
    // The message quotes the index as the file writes it (1-based).
    assert!(err.to_string().contains("vertex index 6,"), "{err}");
    let bad = OBJ.replace("f -4//1 -1//1 -3//1", "f -9 -1 -3");
    let err = load_bytes(bad.as_bytes(), Format::Obj, Path::new("bad.obj")).unwrap_err();
    assert!(err.to_string().contains("relative index -9"), "{err}");
}

#[test]
fn non_finite_names_vertex() {
    let err = off_err(&OFF.replace("1 1 0\n", "1 nan 0\n"));
    assert!(
        matches!(
            err,
            MeshError::NonFinite {
                vertex: 2,
                place: Place::Line(7),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("vertex 2"), "{err}");
    // 1e39 overflows f32.
    let err = off_err(&OFF.replace("0.5 0.5 1.5", "0.5 1e39 1.5"));
    assert!(
        matches!(err, MeshError::NonFinite { vertex: 4, .. }),
        "{err:?}"
    );

    let err = load_bytes(
        OBJ.replace("v 1 0 0", "v 1 0 inf").as_bytes(),
        Format::Obj,
        Path::new("x.obj"),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::NonFinite {
                vertex: 1,
                place: Place::Line(5),
                ..
            }
        ),
        "{err:?}"
    );

    let mut bytes = ply_binary(true);
    let header = body_start(&bytes);
    let v3 = header + 3 * 28;
    bytes[v3 + 8..v3 + 16].copy_from_slice(&f64::INFINITY.to_be_bytes());
    let err = load_bytes(&bytes, Format::Ply, Path::new("x.ply")).unwrap_err();
    assert!(
        matches!(err, MeshError::NonFinite { vertex: 3, place: Place::Byte(b), .. } if b == v3 as u64),
        "{err:?}"
    );

    let mut bytes = stl_binary();
    bytes[84 + 50 + 12 + 12 + 4..84 + 50 + 12 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = load_bytes(&bytes, Format::Stl, Path::new("x.stl")).unwrap_err();
    assert!(
        matches!(err, MeshError::NonFinite { vertex: 3, .. }),
        "{err:?}"
    );
}

#[test]
fn no_faces() {
    let err = off_err("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
    assert!(matches!(err, MeshError::NoFaces { .. }), "{err:?}");
    assert!(err.to_string().contains("no faces"), "{err}");
    let ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
               property float z\nend_header\n0 0 0\n";
    let err = load_bytes(ply.as_bytes(), Format::Ply, Path::new("x.ply")).unwrap_err();
    assert!(matches!(err, MeshError::NoFaces { .. }), "{err:?}");
    let err = load_bytes(b"v 0 0 0\nv 1 0 0\n", Format::Obj, Path::new("x.obj")).unwrap_err();
    assert!(matches!(err, MeshError::NoFaces { .. }), "{err:?}");
    let err = load_bytes(b"solid x\nendsolid x\n", Format::Stl, Path::new("x.stl")).unwrap_err();
    assert!(matches!(err, MeshError::NoFaces { .. }), "{err:?}");
}

#[test]
fn malformed_names_line_and_token() {
    let err = off_err(&OFF.replace("1 1 0\n", "1 x1 0\n"));
    assert!(
        matches!(
            err,
            MeshError::Malformed {
                place: Place::Line(7),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("\"x1\""), "{err}");
    let err = off_err("PLY\n");
    assert!(err.to_string().contains("not an OFF file"), "{err}");
    let err = off_err(&OFF.replace("3 1 4 2", "2 1 4"));
    assert!(err.to_string().contains("at least 3"), "{err}");
    let err = load_bytes(
        b"ply\nformat foo 1.0\nend_header\n",
        Format::Ply,
        Path::new("x.ply"),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::Malformed {
                place: Place::Line(2),
                ..
            }
        ),
        "{err:?}"
    );
    let err = load_bytes(b"f 0 1 2\n", Format::Obj, Path::new("x.obj")).unwrap_err();
    assert!(err.to_string().contains("start at 1"), "{err}");
}

/// A huge count announced by a header must neither allocate nor hang.
#[test]
fn huge_counts_do_not_allocate() {
    let off = "OFF\n4000000000 4000000000 0\n0 0 0\n";
    assert!(matches!(off_err(off), MeshError::Truncated { .. }));
    let mut stl = stl_binary();
    stl[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = load_bytes(&stl, Format::Stl, Path::new("x.stl")).unwrap_err();
    assert!(matches!(err, MeshError::Truncated { .. }), "{err:?}");
    let mut ply = ply_binary(false);
    let at = ply
        .windows(16)
        .position(|w| w == b"element vertex 5")
        .unwrap();
    ply.splice(at..at + 16, b"element vertex 4294967295".iter().copied());
    let err = load_bytes(&ply, Format::Ply, Path::new("x.ply")).unwrap_err();
    assert!(matches!(err, MeshError::Truncated { .. }), "{err:?}");
}

/// Truncates `bytes` to `cut` (when given) and flips the given bits.
fn mutate(bytes: &[u8], cut: Option<usize>, flips: &[(usize, u8)]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    if let Some(cut) = cut {
        out.truncate(cut % (bytes.len() + 1));
    }
    if !out.is_empty() {
        let n = out.len();
        for &(pos, bit) in flips {
            out[pos % n] ^= 1 << (bit % 8);
        }
    }
    out
}

fn no_panic(bytes: &[u8], format: Format) {
    let name = Path::new("mutated");
    if let Ok(mesh) = load_bytes(bytes, format, name) {
        // Loaders read coordinates as written; only their range is left
        // for `validate` to refuse.
        match mesh.validate("mutated") {
            Ok(()) | Err(MeshError::CoordinateTooLarge { .. }) => {}
            Err(e) => panic!("{e}"),
        }
    }
}

fn mutations() -> impl Strategy<Value = (Option<usize>, Vec<(usize, u8)>)> {
    (
        proptest::option::of(0usize..10_000),
        proptest::collection::vec((0usize..10_000, 0u8..8), 0..6),
    )
}

// 256 cases per test (proptest's default; set PROPTEST_CASES to fuzz longer).
proptest! {
    #[test]
    fn mutated_off_never_panics((cut, flips) in mutations()) {
        no_panic(&mutate(OFF.as_bytes(), cut, &flips), Format::Off);
    }

    #[test]
    fn mutated_ply_never_panics((cut, flips) in mutations(), which in 0usize..3) {
        let bytes = match which {
            0 => PLY_ASCII.as_bytes().to_vec(),
            1 => ply_binary(false),
            _ => ply_binary(true),
        };
        no_panic(&mutate(&bytes, cut, &flips), Format::Ply);
    }

    #[test]
    fn mutated_obj_never_panics((cut, flips) in mutations()) {
        no_panic(&mutate(OBJ.as_bytes(), cut, &flips), Format::Obj);
    }

    #[test]
    fn mutated_stl_never_panics((cut, flips) in mutations(), binary in any::<bool>()) {
        let bytes = if binary { stl_binary() } else { STL_ASCII.as_bytes().to_vec() };
        no_panic(&mutate(&bytes, cut, &flips), Format::Stl);
    }

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..300), f in 0usize..4) {
        let format = [Format::Off, Format::Ply, Format::Obj, Format::Stl][f];
        no_panic(&bytes, format);
    }
}

#[test]
fn ply_writer_streams_the_saved_bytes_and_refuses_wrong_counts() {
    use cbvh::mesh::PlyWriter;
    use std::io::ErrorKind;
    let dir = temp_dir("ply-writer");
    let mesh = sample();
    let path = dir.join("m.ply");
    save(&mesh, &path).unwrap();
    let saved = std::fs::read(&path).unwrap();
    let (nv, nt) = (mesh.vertices.len() as u64, mesh.triangles.len() as u64);

    // One element per batch gives the same bytes as save.
    let mut ply = PlyWriter::new(Vec::new(), nv, nt).unwrap();
    assert_eq!(ply.counts(), (nv, nt));
    for v in &mesh.vertices {
        ply.write_vertices(std::slice::from_ref(v)).unwrap();
    }
    for t in &mesh.triangles {
        ply.write_triangles(std::slice::from_ref(t)).unwrap();
    }
    assert_eq!(ply.written(), (nv, nt));
    assert_eq!(ply.finish().unwrap(), saved);

    let refused = |r: std::io::Result<()>| {
        let e = r.unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput, "{e}");
        e.to_string()
    };
    // Too many vertices: refused, nothing written.
    let mut ply = PlyWriter::new(Vec::new(), nv - 1, nt).unwrap();
    let msg = refused(ply.write_vertices(&mesh.vertices));
    assert!(msg.contains("vertices"), "{msg}");
    assert_eq!(ply.written(), (0, 0));
    // Triangles before the last vertex.
    let mut ply = PlyWriter::new(Vec::new(), nv, nt).unwrap();
    ply.write_vertices(&mesh.vertices[1..]).unwrap();
    let msg = refused(ply.write_triangles(&mesh.triangles));
    assert!(msg.contains("before the last vertex"), "{msg}");
    // Too many triangles.
    ply.write_vertices(&mesh.vertices[..1]).unwrap();
    let msg = refused(ply.write_triangles(&[mesh.triangles[0]; 4]));
    assert!(msg.contains("triangles"), "{msg}");
    // Too few at the end: finish fails.
    ply.write_triangles(&mesh.triangles[..1]).unwrap();
    let e = ply.finish().unwrap_err();
    assert_eq!(e.kind(), ErrorKind::InvalidInput);
    assert!(e.to_string().contains("announces"), "{e}");
    let _ = std::fs::remove_dir_all(dir);
}
