//! VTK PolyData files (.vtp XML, .vtk legacy): round trips of meshes, polylines and point/cell data
//! through every encoding we write, files laid out as VTK itself writes them (compressed, base64,
//! big endian, several pieces), and malformed files, which must give a clear error, never a panic.
use vesselmsr::io::*;

#[test]
fn vtp_round_trip_every_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let pd = PolyData {
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.1 + 0.2, 1.0 / 3.0, 7.0],
        ],
        polys: vec![vec![0, 1, 2], vec![0, 2, 3, 1]],
        lines: vec![vec![0, 3], vec![1, 2, 3]],
        point_data: vec![DataArray::scalars(
            "detail",
            DataValues::F32(vec![0.5, 1.5, -2.0, 3.25]),
        )],
        cell_data: vec![
            DataArray::scalars("inpainted", DataValues::U8(vec![10, 11, 20, 21])),
            DataArray {
                name: "v & <w>".into(),
                components: 2,
                values: DataValues::F64(vec![1., 2., 3., 4., 5., 6., 7., 8.]),
            },
            DataArray::scalars("id", DataValues::I32(vec![-1, 2, -3, 4])),
        ],
    };
    for (name, enc) in [
        ("ascii", VtpEncoding::Ascii),
        ("base64", VtpEncoding::Base64),
        ("appended", VtpEncoding::Appended),
    ] {
        let path = dir.path().join(format!("{name}.vtp"));
        let mut bytes = Vec::new();
        write_vtp_encoded_to(&mut bytes, &pd, enc).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        let back = read_vtp(&path).unwrap();
        assert_eq!(back, pd, "{name}");
    }
}
