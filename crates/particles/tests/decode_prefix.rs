//! "Decode what has arrived": a prefix of a stream cut anywhere decodes
//! every complete chunk before the cut and says where it stopped; the
//! strict decoder refuses the same prefix.
use lodkit_mesh::Model;
use lodkit_particles::{
    ChunkReader, DecodeOptions, EncodeOptions, HEADER_LEN, TriangulateOptions, decode,
    decode_prefix,
};

fn stream() -> Vec<u8> {
    let sphere = Model::Mesh(lodkit_mesh::shapes::icosphere(4));
    let opts = EncodeOptions {
        depth: Some(6),
        ..EncodeOptions::DEFAULT
    };
    lodkit_particles::encode(&sphere, &opts).unwrap().bytes
}

#[test]
fn a_prefix_cut_inside_a_chunk_decodes_the_chunks_before_it() {
    let bytes = stream();
    let ends: Vec<usize> = ChunkReader::new(&bytes).map(|c| c.unwrap().end).collect();
    let full = decode(&bytes, &DecodeOptions::default()).unwrap();
    assert!(full.cut.is_none());
    for (k, pair) in ends.windows(2).enumerate() {
        let cut = (pair[0] + pair[1]) / 2;
        let prefix = &bytes[..cut];
        let d = decode_prefix(prefix, &DecodeOptions::default()).unwrap();
        assert_eq!(d.bytes_read, pair[0], "cut in chunk {}", k + 1);
        let c = d.cut.as_ref().expect("the cut is reported");
        assert_eq!((c.chunk, c.offset), (k + 1, pair[0]));
        assert!(decode(prefix, &DecodeOptions::default()).is_err());
        // The same levels as the whole chunks alone.
        let whole = decode(&bytes[..pair[0]], &DecodeOptions::default()).unwrap();
        assert_eq!(d.finest_level(), whole.finest_level());
        assert_eq!(d.q, whole.q);
    }
}

#[test]
fn a_prefix_of_whole_chunks_decodes_with_no_cut_and_triangulates() {
    let bytes = stream();
    let ends: Vec<usize> = ChunkReader::new(&bytes).map(|c| c.unwrap().end).collect();
    for &end in &ends {
        let d = decode_prefix(&bytes[..end], &DecodeOptions::default()).unwrap();
        assert!(d.cut.is_none());
        assert_eq!(d.bytes_read, end);
        let t = d
            .triangulate(d.finest_level(), &TriangulateOptions::DEFAULT)
            .unwrap();
        assert_eq!(
            t.mesh.positions.len(),
            d.surface(d.finest_level()).unwrap().cells.len()
        );
    }
}

#[test]
fn a_prefix_without_a_complete_level_is_an_error() {
    let bytes = stream();
    for cut in [0, 10, HEADER_LEN, HEADER_LEN + 5] {
        assert!(decode_prefix(&bytes[..cut], &DecodeOptions::default()).is_err());
    }
}
