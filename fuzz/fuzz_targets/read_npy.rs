//! Any bytes: parsing a `.npy` never panics and holds at most `linear_bound` bytes while
//! it reads; an array that parses has as many elements as its shape says, and writing it
//! back gives an array that parses to the same.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use weft_fuzz::{bounded, linear_bound};
use weft_mesh::export::npy::{parse_npy, write_npy_to, NpyArray, NpyData};

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.npy");
    let (read, _) = bounded(data.len(), linear_bound(data.len()), || parse_npy(data, path));
    let Ok(array) = read else {
        return;
    };
    let count: usize = array.shape.iter().product();
    assert_eq!(array.data.len(), count, "shape {:?}", array.shape);
    let mut bytes = Vec::new();
    let shape = &array.shape;
    match &array.data {
        NpyData::F32(v) => write_npy_to(&mut bytes, shape, v),
        NpyData::F64(v) => write_npy_to(&mut bytes, shape, v),
        NpyData::I32(v) => write_npy_to(&mut bytes, shape, v),
        NpyData::I64(v) => write_npy_to(&mut bytes, shape, v),
        NpyData::U32(v) => write_npy_to(&mut bytes, shape, v),
        NpyData::U8(v) => write_npy_to(&mut bytes, shape, v),
    }
    .expect("writing to memory");
    let back: NpyArray = parse_npy(&bytes, path).expect("a written array parses");
    assert_eq!(back.shape, array.shape);
    // Bitwise, so NaNs compare equal.
    assert_eq!(format!("{:?}", back.data), format!("{:?}", array.data));
});
