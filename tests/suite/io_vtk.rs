//! VTK PolyData files (.vtp XML, .vtk legacy): round trips of meshes, polylines and point/cell data
//! through every encoding we write, files laid out as VTK itself writes them (zlib-compressed
//! base64 with UInt32 headers, big endian, several pieces, verts and strips, VTK 9's legacy
//! OFFSETS/CONNECTIVITY), and malformed files, which must give a clear error, never a panic.
//! (Reading our files back with VTK itself is reference/test_vtk_formats.py.)

use crate::common;
use base64::Engine;
use common::*;
use std::io::Write;
use std::path::Path;
use vesselmsr::io::*;
use vesselmsr::Error;

/// Points, a triangle, a quad, two polylines, and point and cell data of every value type,
/// one array with 2 and one with 5 components, names needing escapes in XML and legacy VTK.
fn sample() -> PolyData {
    PolyData {
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.1 + 0.2, 1.0 / 3.0, 7.0],
        ],
        polys: vec![vec![0, 1, 2], vec![0, 2, 3, 1]],
        lines: vec![vec![0, 3], vec![1, 2, 3]],
        point_data: vec![
            DataArray::scalars("detail", DataValues::F32(vec![0.5, 1.5, -2.0, 3.25])),
            DataArray::scalars("label", DataValues::I32(vec![-7, 0, 1 << 30, 3])),
        ],
        cell_data: vec![
            DataArray::scalars("inpainted", DataValues::U8(vec![10, 11, 20, 21])),
            DataArray {
                name: "v & <w> 100%".into(),
                components: 2,
                values: DataValues::F64((1..=8).map(|k| k as f64 / 3.0).collect()),
            },
            DataArray {
                name: "five".into(),
                components: 5,
                values: DataValues::F32((0..20).map(|k| k as f32 * 0.1).collect()),
            },
        ],
    }
}

#[test]
fn vtp_round_trip_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let pd = sample();
    for (name, enc) in [
        ("ascii", VtpEncoding::Ascii),
        ("base64", VtpEncoding::Base64),
        ("appended", VtpEncoding::Appended),
    ] {
        let path = dir.path().join(format!("{name}.vtp"));
        let mut bytes = Vec::new();
        write_vtp_encoded_to(&mut bytes, &pd, enc).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read_vtp(&path).unwrap(), pd, "{name}");
    }
    // write_vtp (atomic) writes the appended form.
    let path = dir.path().join("atomic.vtp");
    write_vtp(&path, &pd).unwrap();
    let mut bytes = Vec::new();
    write_vtp_to(&mut bytes, &pd).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    assert!(bytes.windows(22).any(|w| w == b"<AppendedData encoding"));
}

#[test]
fn vtk_legacy_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let pd = sample();
    let path = dir.path().join("s.vtk");
    write_vtk_legacy(&path, &pd).unwrap();
    let text = std::fs::read(&path).unwrap();
    assert!(text.starts_with(b"# vtk DataFile Version 4.2\nvesselmsr\nBINARY\nDATASET POLYDATA\n"));
    // The first array is the active SCALARS, the others in a FIELD; names with spaces and '%'
    // are escaped.
    assert!(text
        .windows(40)
        .any(|w| w == b"SCALARS inpainted unsigned_char 1\nLOOKUP"));
    assert!(text
        .windows(32)
        .any(|w| w == b"v%20&%20<w>%20100%25 2 4 double\n"));
    assert!(text.windows(17).any(|w| w == b"five 5 4 float\n\x00\x00"));
    assert_eq!(read_vtk_legacy(&path).unwrap(), pd);
}

#[test]
fn mesh_round_trip_is_exact_through_both_formats() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let detail: Vec<f32> = (0..6).map(|k| k as f32 / 7.0).collect();
    let flag: Vec<f32> = (0..8).map(|k| (k % 3 == 0) as u8 as f32).collect();
    for ext in ["vtp", "VTK", "Vtp", "vtk"] {
        let path = dir.path().join(format!("m.{ext}"));
        write_mesh(&path, &mesh).unwrap();
        let back = read_mesh(&path).unwrap();
        assert_eq!(back.vertices, mesh.vertices, "{ext}");
        assert_eq!(back.faces, mesh.faces, "{ext}");

        write_mesh_with_fields(
            &path,
            &mesh,
            &[("detail", &detail)],
            &[("inpainted", &flag)],
        )
        .unwrap();
        let (back, fields) = read_mesh_with_scalars(&path).unwrap();
        assert_eq!(
            (back.vertices, back.faces),
            (mesh.vertices.clone(), mesh.faces.clone())
        );
        assert_eq!(fields, vec![("detail".to_string(), detail.clone())]);
        let pd = if ext.eq_ignore_ascii_case("vtp") {
            read_vtp(&path).unwrap()
        } else {
            read_vtk_legacy(&path).unwrap()
        };
        assert_eq!(
            pd.cell_data,
            vec![DataArray::scalars(
                "inpainted",
                DataValues::F32(flag.clone())
            )]
        );

        write_mesh_with_scalars(&path, &mesh, &[("detail", &detail)]).unwrap();
        assert_eq!(read_mesh_with_scalars(&path).unwrap().1[0].1, detail);
    }
}

#[test]
fn fields_that_do_not_fit_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = odd_octahedron();
    let six = [0.0f32; 6];
    let eight = [0.0f32; 8];
    type Fields<'a> = Vec<(&'a str, &'a [f32])>;
    let cases: Vec<(&str, Fields, Fields, &str)> = vec![
        ("a.ply", vec![], vec![("f", &eight[..])], ".vtp or .vtk"),
        ("a.stl", vec![("p", &six[..])], vec![], ".ply, .vtp or .vtk"),
        (
            "a.vtp",
            vec![("p", &eight[..])],
            vec![],
            "8 values but the mesh has 6 vertices",
        ),
        (
            "a.vtk",
            vec![],
            vec![("f", &six[..])],
            "6 values but the mesh has 8 triangles",
        ),
        (
            "a.vtp",
            vec![],
            vec![("f", &eight[..]), ("f", &eight[..])],
            "twice",
        ),
        ("a.vtk", vec![("", &six[..])], vec![], "empty name"),
    ];
    for (file, points, faces, words) in cases {
        let path = dir.path().join(file);
        let e = write_mesh_with_fields(&path, &mesh, &points, &faces).unwrap_err();
        assert!(matches!(e, Error::Format { .. }), "{e:?}");
        let e = e.to_string();
        assert!(e.contains(words) && e.contains(file), "{file}: {e}");
        assert!(!path.exists());
    }
}

/// A tiny vtp as VTK lays it out, with two pieces, verts and strips, built from DataArray texts.
fn two_piece_ascii() -> String {
    let piece = |pts: &str, shift: i32| {
        format!(
            r#"<Piece NumberOfPoints="5" NumberOfVerts="1" NumberOfLines="1" NumberOfStrips="1" NumberOfPolys="1">
  <PointData><DataArray type="Float32" Name="t" format="ascii">{t}</DataArray></PointData>
  <CellData>
    <DataArray type="Int64" Name="id" format="ascii">{c}</DataArray>
    <DataArray type="String" Name="skipped" format="ascii">65 0</DataArray>
  </CellData>
  <Points><DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">{pts}</DataArray></Points>
  <Verts><DataArray type="Int64" Name="connectivity" format="ascii">4</DataArray><DataArray type="Int64" Name="offsets" format="ascii">1</DataArray></Verts>
  <Lines><DataArray type="Int32" Name="connectivity" format="ascii">0 4</DataArray><DataArray type="Int32" Name="offsets" format="ascii">2</DataArray></Lines>
  <Strips><DataArray type="UInt32" Name="connectivity" format="ascii">0 1 2 3</DataArray><DataArray type="Int32" Name="offsets" format="ascii">4</DataArray></Strips>
  <Polys><DataArray type="Int16" Name="connectivity" format="ascii">1 2 3</DataArray><DataArray type="Int16" Name="offsets" format="ascii">3</DataArray></Polys>
</Piece>"#,
            t = (0..5)
                .map(|k| (k + shift).to_string())
                .collect::<Vec<_>>()
                .join(" "),
            c = (0..4)
                .map(|k| (10 * shift + k).to_string())
                .collect::<Vec<_>>()
                .join(" "),
        )
    };
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\">\n<PolyData>\n\
         <FieldData><DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">3</DataArray></FieldData>\n\
         {}\n{}\n</PolyData>\n</VTKFile>\n",
        piece("0 0 0 1 0 0 1 1 0 0 1 0 9 9 9", 0),
        piece("0 0 1 1 0 1 1 1 1 0 1 1 8 8 8", 1)
    )
}

#[test]
fn vtp_pieces_verts_and_strips() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(dir.path(), "p.vtp", two_piece_ascii().as_bytes());
    let pd = read_vtp(&path).unwrap();
    assert_eq!(pd.points.len(), 10);
    assert_eq!(pd.points[7], [1.0, 1.0, 1.0]);
    assert_eq!(pd.lines, vec![vec![0, 4], vec![5, 9]]);
    // Each piece: its polygon, then its strip's two triangles (second one re-wound).
    assert_eq!(
        pd.polys,
        vec![
            vec![1, 2, 3],
            vec![0, 1, 2],
            vec![2, 1, 3],
            vec![6, 7, 8],
            vec![5, 6, 7],
            vec![7, 6, 8]
        ]
    );
    assert_eq!(pd.point_data.len(), 1);
    assert_eq!(
        pd.point_data[0].values,
        DataValues::F32(vec![0., 1., 2., 3., 4., 1., 2., 3., 4., 5.])
    );
    // Cell data: lines of both pieces, then polys (strip tuples repeated); verts dropped.
    assert_eq!(pd.cell_data.len(), 1, "the String array is skipped");
    assert_eq!(
        pd.cell_data[0].values,
        DataValues::I32(vec![1, 11, 2, 3, 3, 12, 13, 13])
    );
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.num_faces(), 6);
}

/// Numbers that know their bytes in either byte order (for hand-built VTK files).
trait EndianBytes: Copy {
    fn bytes(self, big: bool) -> Vec<u8>;
}

macro_rules! endian_bytes {
    ($($t:ty),*) => {$(
        impl EndianBytes for $t {
            fn bytes(self, big: bool) -> Vec<u8> {
                if big { self.to_be_bytes().to_vec() } else { self.to_le_bytes().to_vec() }
            }
        }
    )*};
}
endian_bytes!(f32, i64, f64);

/// `values` as raw bytes, big or little endian.
fn packed<T: EndianBytes>(values: &[T], big: bool) -> Vec<u8> {
    values.iter().flat_map(|x| x.bytes(big)).collect()
}

/// VTK's default writer layout: zlib-compressed blocks, UInt32 headers, the header base64-encoded
/// apart from the data; here inline (format="binary") and in base64 appended data, and big endian.
#[test]
fn vtp_compressed_and_big_endian_as_vtk_writes_them() {
    let dir = tempfile::tempdir().unwrap();
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    // Two blocks of at most 16 bytes each, per array.
    let compressed = |raw: &[u8], big: bool| -> String {
        let blocks: Vec<&[u8]> = raw.chunks(16).collect();
        let packed: Vec<Vec<u8>> = blocks
            .iter()
            .map(|b| {
                let mut z =
                    flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
                z.write_all(b).unwrap();
                z.finish().unwrap()
            })
            .collect();
        let word = |v: u32| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        };
        let mut header = Vec::new();
        header.extend(word(blocks.len() as u32));
        header.extend(word(16));
        header.extend(word(blocks.last().map_or(0, |b| b.len() as u32 % 16)));
        for p in &packed {
            header.extend(word(p.len() as u32));
        }
        b64(&header) + &b64(&packed.concat())
    };
    let pts: [f32; 12] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.];
    let conn: [i64; 12] = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
    let offs: [i64; 4] = [3, 6, 9, 12];
    let detail: [f64; 4] = [0.25, -1.0, 1e300, 7.0];
    for big in [false, true] {
        let bytes = |v: &[u8]| v.to_vec();
        let arrays = [
            ("Float32", "Points", 3, packed(&pts, big)),
            ("Int64", "connectivity", 1, packed(&conn, big)),
            ("Int64", "offsets", 1, packed(&offs, big)),
            ("Float64", "detail", 1, packed(&detail, big)),
            ("UInt8", "flag", 1, bytes(&[1, 0, 0, 1])),
        ];
        let order = if big { "BigEndian" } else { "LittleEndian" };
        let head = format!("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"{order}\" header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">\n<PolyData>\n<Piece NumberOfPoints=\"4\" NumberOfPolys=\"4\">\n");
        // Inline: each array's text in its element. Appended: offsets into one base64 text.
        let mut inline = head.clone();
        let mut appended = head.clone();
        let mut text = String::new();
        let tags = |section: &str| match section {
            "Points" => ("<Points>", "</Points>"),
            "detail" => ("<PointData>", "</PointData>"),
            "flag" => ("<CellData>", "</CellData>"),
            _ => ("<Polys>", "</Polys>"),
        };
        for (k, (ty, name, comps, raw)) in arrays.iter().enumerate() {
            let (open, close) = tags(name);
            let enc = compressed(raw, big);
            let open_now = k != 2;
            let close_now = k != 1;
            let o = if open_now { open } else { "" };
            let c = if close_now { close } else { "" };
            inline += &format!("{o}<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"binary\">\n  {enc}\n</DataArray>{c}\n");
            appended += &format!("{o}<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"{}\"/>{c}\n", text.len());
            text += &enc;
        }
        inline += "</Piece>\n</PolyData>\n</VTKFile>\n";
        appended += &format!("</Piece>\n</PolyData>\n<AppendedData encoding=\"base64\">\n   _{text}\n</AppendedData>\n</VTKFile>\n");
        for (what, content) in [("inline", inline), ("appended", appended)] {
            let path = write_file(dir.path(), "c.vtp", content.as_bytes());
            let pd = read_vtp(&path).unwrap_or_else(|e| panic!("{what} big={big}: {e}"));
            assert_eq!(pd.points[3], [0.0, 0.0, 1.0]);
            assert_eq!(
                pd.polys,
                conn.chunks(3)
                    .map(|c| c.iter().map(|&v| v as u32).collect::<Vec<_>>())
                    .collect::<Vec<_>>()
            );
            assert_eq!(pd.point_data[0].values, DataValues::F64(detail.to_vec()));
            assert_eq!(pd.cell_data[0].values, DataValues::U8(vec![1, 0, 0, 1]));
        }
    }
}

#[test]
fn vtk_legacy_layouts_as_vtk_writes_them() {
    let dir = tempfile::tempdir().unwrap();
    // VTK 9's ASCII layout: OFFSETS/CONNECTIVITY, METADATA blocks, FIELD arrays, NORMALS.
    let v51 = "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\n\
        FIELD FieldData 1\nTimeValue 1 1 double\n2.5\n\
        POINTS 4 float\n0 0 0 1 0 0 0 1 0\n0 0 1\n\
        METADATA\nINFORMATION 1\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0 1\n\n\
        POLYGONS 3 6\nOFFSETS vtktypeint64\n0 3 6\nCONNECTIVITY vtktypeint64\n0 2 1 0 1 3\n\
        TRIANGLE_STRIPS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n1 2 3 0\n\
        CELL_DATA 3\nFIELD FieldData 1\ninpainted 1 3 unsigned_char\n1 0 1\nMETADATA\nINFORMATION 0\n\n\
        POINT_DATA 4\nNORMALS Normals float\n1 0 0 0 1 0 0 0 1 1 1 1\n\
        SCALARS my%20detail double 1\nLOOKUP_TABLE default\n0.5 1.5 2.5 3.5\n";
    let path = write_file(dir.path(), "v51.vtk", v51.as_bytes());
    let pd = read_vtk_legacy(&path).unwrap();
    assert_eq!(
        pd.polys,
        vec![vec![0, 2, 1], vec![0, 1, 3], vec![1, 2, 3], vec![3, 2, 0]]
    );
    assert_eq!(pd.cell_data[0].values, DataValues::U8(vec![1, 0, 1, 1]));
    assert_eq!(pd.point_data[0].name, "Normals");
    assert_eq!(pd.point_data[0].components, 3);
    assert_eq!(pd.point_data[1].name, "my detail");
    assert_eq!(
        pd.point_data[1].values,
        DataValues::F64(vec![0.5, 1.5, 2.5, 3.5])
    );
    assert_eq!(read_mesh(&path).unwrap().num_faces(), 4);

    // The classic layout in BINARY: sizes before indices, a VERTICES cell, SCALARS with the
    // component count, COLOR_SCALARS as bytes.
    let mut b =
        b"# vtk DataFile Version 3.0\ntitle\nBINARY\nDATASET POLYDATA\nPOINTS 4 double\n".to_vec();
    for x in [0.0f64, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.] {
        b.extend(x.to_be_bytes());
    }
    b.extend(b"\nVERTICES 1 2\n");
    for v in [1i32, 3] {
        b.extend(v.to_be_bytes());
    }
    b.extend(b"\nPOLYGONS 1 5\n");
    for v in [4i32, 0, 1, 2, 3] {
        b.extend(v.to_be_bytes());
    }
    b.extend(b"\nCELL_DATA 2\nSCALARS id int 1\nLOOKUP_TABLE default\n");
    for v in [-5i32, 6] {
        b.extend(v.to_be_bytes());
    }
    b.extend(b"\nCOLOR_SCALARS rgb 3\n\x01\x02\x03\x04\x05\x06\n");
    let path = write_file(dir.path(), "classic.vtk", &b);
    let pd = read_vtk_legacy(&path).unwrap();
    assert_eq!(pd.polys, vec![vec![0, 1, 2, 3]]);
    assert_eq!(pd.points[1], [1.0, 0.0, 0.0]);
    assert_eq!(pd.cell_data[0].values, DataValues::I32(vec![6]));
    assert_eq!(pd.cell_data[1].values, DataValues::U8(vec![4, 5, 6]));
    // The quad is fan-triangulated on mesh read.
    assert_eq!(read_mesh(&path).unwrap().faces, vec![[0, 1, 2], [0, 2, 3]]);
}

/// Whatever prefix of a file is read, the result is an error naming the file, or data equal to
/// the original's (a legacy file may end after any complete section: then what is there must match).
#[test]
fn truncated_files_give_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let pd = sample();
    let mut files: Vec<(&str, Vec<u8>)> = Vec::new();
    for enc in [
        VtpEncoding::Ascii,
        VtpEncoding::Base64,
        VtpEncoding::Appended,
    ] {
        let mut b = Vec::new();
        write_vtp_encoded_to(&mut b, &pd, enc).unwrap();
        files.push(("t.vtp", b));
    }
    let mut b = Vec::new();
    write_vtk_legacy_to(&mut b, &pd).unwrap();
    files.push(("t.vtk", b));
    let (mut errors, mut complete) = (0, 0);
    for (name, bytes) in &files {
        let path = dir.path().join(name);
        for cut in 0..bytes.len() {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            let read = if name.ends_with("vtp") {
                read_vtp(&path)
            } else {
                read_vtk_legacy(&path)
            };
            match read {
                Err(e) => {
                    assert!(matches!(e, Error::Format { .. }), "{e:?}");
                    assert!(e.to_string().contains(name), "{e}");
                    errors += 1;
                }
                Ok(back) => {
                    complete += 1;
                    // A legacy file has no end marker: it may stop after any whole section.
                    assert_eq!(back.points, pd.points, "cut {cut}");
                    assert!(back.polys == pd.polys || back.polys.is_empty(), "cut {cut}");
                    assert!(back.lines == pd.lines || back.lines.is_empty(), "cut {cut}");
                    for a in back.point_data.iter().chain(&back.cell_data) {
                        assert!(
                            pd.point_data.contains(a) || pd.cell_data.contains(a),
                            "cut {cut}: {a:?}"
                        );
                    }
                    assert!(name.ends_with("vtk") || back == pd, "cut {cut}");
                }
            }
        }
    }
    println!("{errors} prefixes refused, {complete} read whole");
    assert!(errors > 4000);
}

fn assert_refused(dir: &Path, name: &str, content: &[u8], words: &[&str]) {
    let path = write_file(dir, name, content);
    let e = if name.ends_with(".vtp") {
        read_vtp(&path)
    } else {
        read_vtk_legacy(&path)
    }
    .unwrap_err();
    let text = e.to_string();
    println!("{text}");
    assert!(matches!(e, Error::Format { .. }), "{e:?}");
    assert!(
        text.contains(name) && words.iter().all(|w| text.contains(w)),
        "{name}: {text}"
    );
    // The mesh reader gives the same kind of error.
    assert!(matches!(read_mesh(&path), Err(Error::Format { .. })));
}

#[test]
fn malformed_vtp_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let mut good = Vec::new();
    write_vtp_to(&mut good, &sample()).unwrap();
    // Replaces text in the bytes (the raw appended data is not UTF-8).
    let edit = |from: &str, to: &str| -> Vec<u8> {
        let at = good
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap();
        [&good[..at], to.as_bytes(), &good[at + from.len()..]].concat()
    };
    let ascii = {
        let mut b = Vec::new();
        write_vtp_encoded_to(&mut b, &sample(), VtpEncoding::Ascii).unwrap();
        String::from_utf8(b).unwrap()
    };
    let huge = u64::MAX.to_string();
    let cases: Vec<(Vec<u8>, Vec<&str>)> = vec![
        (
            edit("NumberOfPoints=\"4\"", "NumberOfPoints=\"5\""),
            vec!["coordinates for 5 points"],
        ),
        (
            edit(
                "NumberOfPoints=\"4\"",
                &format!("NumberOfPoints=\"{huge}\""),
            ),
            vec!["point"],
        ),
        (
            edit("NumberOfPolys=\"2\"", "NumberOfPolys=\"3\""),
            vec!["Polys", "2 offsets for 3 cells"],
        ),
        (
            edit("NumberOfPolys=\"2\"", "NumberOfPolys=\"-2\""),
            vec!["not a count"],
        ),
        (
            ascii.replace("0 1 2 0 2 3 1", "0 1 2 0 2 9 1").into_bytes(),
            vec!["Polys", "point 9", "4 points"],
        ),
        (
            ascii
                .replace("0 1 2 0 2 3 1", "0 1 2 0 2 -3 1")
                .into_bytes(),
            vec!["point -3"],
        ),
        (
            ascii.replace("\n3 7\n", "\n7 3\n").into_bytes(),
            vec!["out of order"],
        ),
        (
            ascii.replace("10 11 20 21", "10 11 20").into_bytes(),
            vec!["inpainted", "3 values", "4 cells"],
        ),
        (
            ascii
                .replace("0.5 1.5 -2.0 3.25", "0.5 1.5 x 3.25")
                .into_bytes(),
            vec!["'x' is not a number"],
        ),
        (
            edit("type=\"PolyData\"", "type=\"ImageData\""),
            vec!["ImageData", "not PolyData"],
        ),
        (
            edit(
                "header_type=\"UInt64\"",
                "header_type=\"UInt64\" compressor=\"vtkLZ4DataCompressor\"",
            ),
            vec!["vtkLZ4DataCompressor"],
        ),
        (
            edit("offset=\"0\"", &format!("offset=\"{huge}\"")),
            vec!["past the end"],
        ),
        (edit("<Polys>", "<Polys><DataArray"), vec!["<DataArray>"]),
        (b"hello".to_vec(), vec!["no <VTKFile>"]),
    ];
    for (k, (content, words)) in cases.iter().enumerate() {
        assert_refused(dir.path(), &format!("bad{k}.vtp"), content, words);
    }
    // A raw appended array whose header declares more bytes than follow, huge or not.
    let mut raw = Vec::new();
    write_vtp_to(&mut raw, &sample()).unwrap();
    let at = raw.windows(2).position(|w| w == b"_\x10").unwrap() + 1;
    for (declared, words) in [
        (
            17u64,
            "17 bytes of data do not hold whole 4-byte values".to_string(),
        ),
        (1 << 40, format!("declares {} bytes", 1u64 << 40)),
        (u64::MAX, format!("declares {} bytes", u64::MAX)),
    ] {
        let mut b = raw.clone();
        b[at..at + 8].copy_from_slice(&declared.to_le_bytes());
        assert_refused(dir.path(), "len.vtp", &b, &["detail", &words]);
    }
    // Base64 that is not, and a compressed block that lies about its inflated size.
    assert_refused(
        dir.path(),
        "b64.vtp",
        &edit(
            "format=\"appended\" offset=\"0\"/>",
            "format=\"binary\">AAA*</DataArray>",
        ),
        &["base64"],
    );
    let lying = format!(
        "<VTKFile type=\"PolyData\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"><PolyData><Piece NumberOfPoints=\"1\">\
         <Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">{}</DataArray></Points></Piece></PolyData></VTKFile>",
        base64::engine::general_purpose::STANDARD.encode(
            [1u64, 1 << 40, 1 << 40, 4].iter().flat_map(|v| v.to_le_bytes()).chain([0x78, 0x9c, 0x03, 0x00]).collect::<Vec<u8>>()
        )
    );
    assert_refused(
        dir.path(),
        "zlib.vtp",
        lying.as_bytes(),
        &["more than zlib allows"],
    );
}

#[test]
fn malformed_vtk_legacy_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n";
    let pts = "POINTS 3 float\n0 0 0 1 0 0 0 1 0\n";
    let cases: Vec<(String, Vec<&str>)> = vec![
        ("hello\n".into(), vec!["not a legacy VTK file"]),
        (head.replace("POLYDATA", "UNSTRUCTURED_GRID"), vec!["UNSTRUCTURED_GRID", "not POLYDATA"]),
        (format!("{head}POINTS 4 float\n0 0 0 1 0 0 0 1 0\n"), vec!["POINTS", "12 values declared"]),
        (format!("{head}POINTS 99999999999999 float\n0 0 0\n"), vec!["POINTS", "299999999999997 values declared"]),
        (format!("{head}POINTS 3 bit\n"), vec!["unsupported data type 'bit'"]),
        (format!("{head}{pts}POLYGONS 1 4\n3 0 1 3\n"), vec!["POLYGONS", "point 3", "3 points"]),
        (format!("{head}{pts}POLYGONS 2 4\n3 0 1 2\n"), vec!["POLYGONS", "end before cell 1"]),
        (format!("{head}{pts}POLYGONS 1 4\n5 0 1 2\n"), vec!["declares 5 points"]),
        (format!("{head}POLYGONS 1 4\n3 0 1 2\n"), vec!["POLYGONS before POINTS"]),
        (format!("{head}{pts}POLYGONS 1 4\n3 0 1 2\nCELL_DATA 1\nSCALARS s float\nLOOKUP_TABLE default\n"), vec!["s: 1 values declared"]),
        (format!("{head}{pts}POLYGONS 1 4\n3 0 1 2\nCELL_DATA 2\nSCALARS s float\nLOOKUP_TABLE default\n1 2\n"), vec!["'s' has 2 values, not 1 cells"]),
        (format!("{head}{pts}SCALARS s float\n1 2 3\n"), vec!["outside POINT_DATA"]),
        (format!("{head}{pts}POINT_DATA 3\nSCALARS s float\n1 2 3\n"), vec!["SCALARS s: LOOKUP_TABLE expected"]),
        (format!("{head}{pts}CELLS 1 4\n"), vec!["unsupported section 'CELLS'"]),
        (format!("{head}{pts}POLYGONS 2 3\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2\n"), vec!["offsets run from 0 to 4"]),
        (format!("{head}{pts}POINT_DATA 3\nSCALARS a float\nLOOKUP_TABLE default\n1 2 3\nSCALARS a float\nLOOKUP_TABLE default\n1 2 3\n"), vec!["'a' is given twice"]),
    ];
    for (k, (content, words)) in cases.iter().enumerate() {
        assert_refused(
            dir.path(),
            &format!("bad{k}.vtk"),
            content.as_bytes(),
            words,
        );
    }
    // BINARY: a POINTS block that declares more bytes than the file has.
    let mut b =
        b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 1000000000 double\n"
            .to_vec();
    b.extend([0u8; 24]);
    assert_refused(
        dir.path(),
        "bin.vtk",
        &b,
        &["POINTS", "3000000000 values declared"],
    );
}

const VTK_READ: &str = r#"
import json, sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
path = sys.argv[1]
r = vtk.vtkXMLPolyDataReader() if path.endswith(".vtp") else vtk.vtkPolyDataReader()
messages = []
r.AddObserver("ErrorEvent", lambda o, e: messages.append(e))
r.AddObserver("WarningEvent", lambda o, e: messages.append(e))
r.SetFileName(path)
r.Update()
pd = r.GetOutput()
def arrays(data):
    out = {}
    for k in range(data.GetNumberOfArrays()):
        a = data.GetArray(k)
        out[a.GetName()] = {"type": a.GetDataTypeAsString(), "components": a.GetNumberOfComponents(),
                            "values": [float(v) for v in vtk_to_numpy(a).ravel()]}
    return out
cells = []
for c in range(pd.GetNumberOfCells()):
    cell = pd.GetCell(c)
    cells.append([pd.GetCellType(c)] + [cell.GetPointId(i) for i in range(cell.GetNumberOfPoints())])
print(json.dumps({"messages": messages, "points": vtk_to_numpy(pd.GetPoints().GetData()).tolist(),
                  "cells": cells, "point_data": arrays(pd.GetPointData()), "cell_data": arrays(pd.GetCellData())}))
"#;

/// VTK's own readers (ParaView's) read our .vtp and .vtk: points, lines then polygons in VTK's cell
/// order, and every point- and cell-data array with its type, components and values.
#[test]
fn vtk_reads_our_lines_polygons_and_data() {
    let dir = tempfile::tempdir().unwrap();
    let pd = sample();
    for name in ["s.vtp", "s.vtk"] {
        let path = dir.path().join(name);
        if name.ends_with("vtp") {
            write_vtp(&path, &pd).unwrap();
        } else {
            write_vtk_legacy(&path, &pd).unwrap();
        }
        let v = run_python(VTK_READ, &[&path]);
        assert_eq!(v["messages"], serde_json::json!([]), "{name}");
        let points: Vec<[f64; 3]> = serde_json::from_value(v["points"].clone()).unwrap();
        assert_eq!(points, pd.points, "{name}");
        // VTK_LINE 3, VTK_POLY_LINE 4, VTK_TRIANGLE 5, VTK_QUAD 9.
        let cells: Vec<Vec<u32>> = serde_json::from_value(v["cells"].clone()).unwrap();
        assert_eq!(
            cells,
            vec![
                vec![3, 0, 3],
                vec![4, 1, 2, 3],
                vec![5, 0, 1, 2],
                vec![9, 0, 2, 3, 1]
            ],
            "{name}"
        );
        for (key, arrays) in [("point_data", &pd.point_data), ("cell_data", &pd.cell_data)] {
            assert_eq!(
                v[key].as_object().unwrap().len(),
                arrays.len(),
                "{name} {key}"
            );
            for a in arrays {
                let got = &v[key][&a.name];
                let ty = match a.values {
                    DataValues::F32(_) => "float",
                    DataValues::F64(_) => "double",
                    DataValues::I32(_) => "int",
                    DataValues::U8(_) => "unsigned char",
                };
                assert_eq!(got["type"], ty, "{name} {}", a.name);
                assert_eq!(got["components"], a.components, "{name} {}", a.name);
                let values: Vec<f64> = serde_json::from_value(got["values"].clone()).unwrap();
                assert_eq!(values, a.values.to_f64(), "{name} {}", a.name);
            }
        }
    }
}
