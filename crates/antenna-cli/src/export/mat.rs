//! A MAT-file writer: level 5 (MATLAB 5 to 7), uncompressed, little-endian, with the classes
//! `antenna export` needs: double, uint8, uint16, uint64, logical, char and cell arrays of two
//! dimensions.
//!
//! Why our own and not matrw 0.1.4 (which the export used before): matrw stores every
//! whole-valued double array with the smallest integer data type that holds it (class double,
//! so MATLAB converts back, but `scipy.io.loadmat` without `mat_dtype=True` returns uint8 or
//! uint16: an all-zero `base_angle_rad` came back as uint8 and `base_angle_rad - 1` wrapped to
//! 255), and it has no option to turn that off; its file output also drops write errors
//! (`let _ =`), so a full disk left a truncated file and a success. The format (the MathWorks
//! document "MAT-File Format", level 5) takes little code for these classes: every array here
//! is written with the data type of its class (`miDOUBLE` for doubles), so it loads as that
//! class everywhere.
//!
//! Layout: a 128-byte header (text, version 0x0100, endian indicator `IM`), then one `miMATRIX`
//! element per variable: array flags (class, logical bit), dimensions, name, data. Elements of
//! at most 4 bytes use the small data element format (tag and data in 8 bytes), as MATLAB and
//! scipy write them; every element is padded to 8 bytes. Char data is UTF-8 (`miUTF8`), one
//! column per character; cell elements are `miMATRIX` elements with an empty name, in
//! column-major order.

use std::io::{self, Write};

/// Data types of the format (tags of data elements).
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_UTF8: u32 = 16;

/// Array classes.
const MX_CELL: u8 = 1;
const MX_CHAR: u8 = 4;
const MX_DOUBLE: u8 = 6;
const MX_UINT8: u8 = 9;
const MX_UINT16: u8 = 11;
const MX_UINT64: u8 = 15;

/// The logical bit of the array flags.
const FLAG_LOGICAL: u8 = 0x02;

/// The header's length, bytes (text, subsystem offset, version, endian indicator).
pub const HEADER_LEN: usize = 128;

/// The longest variable name MATLAB accepts.
const MAX_NAME_LEN: usize = 63;

/// An array's values, column-major.
#[derive(Debug, Clone, PartialEq)]
pub enum Data {
    /// Class double (`miDOUBLE`): loads as double in MATLAB, float64 in scipy.
    Double(Vec<f64>),
    /// Class uint8.
    Uint8(Vec<u8>),
    /// Class uint16.
    Uint16(Vec<u16>),
    /// Class uint64.
    Uint64(Vec<u64>),
    /// Class logical (uint8 data with the logical flag; scipy loads it as uint8 0/1).
    Logical(Vec<bool>),
    /// Class char: the text of a 1 x L array (L characters), or of a 0 x 0 one when empty.
    Char(String),
    /// Class cell: the elements, column-major.
    Cell(Vec<Array>),
}

impl Data {
    /// The number of elements.
    fn len(&self) -> usize {
        match self {
            Data::Double(v) => v.len(),
            Data::Uint8(v) => v.len(),
            Data::Uint16(v) => v.len(),
            Data::Uint64(v) => v.len(),
            Data::Logical(v) => v.len(),
            Data::Char(s) => s.chars().count(),
            Data::Cell(v) => v.len(),
        }
    }

    /// The class and the flags byte.
    fn class(&self) -> (u8, u8) {
        match self {
            Data::Double(_) => (MX_DOUBLE, 0),
            Data::Uint8(_) => (MX_UINT8, 0),
            Data::Uint16(_) => (MX_UINT16, 0),
            Data::Uint64(_) => (MX_UINT64, 0),
            Data::Logical(_) => (MX_UINT8, FLAG_LOGICAL),
            Data::Char(_) => (MX_CHAR, 0),
            Data::Cell(_) => (MX_CELL, 0),
        }
    }

    /// The data element's type and its payload's length in bytes (`None` for a cell, whose
    /// elements are arrays).
    fn element(&self) -> Option<(u32, usize)> {
        match self {
            Data::Double(v) => Some((MI_DOUBLE, 8 * v.len())),
            Data::Uint8(v) => Some((MI_UINT8, v.len())),
            Data::Uint16(v) => Some((MI_UINT16, 2 * v.len())),
            Data::Uint64(v) => Some((MI_UINT64, 8 * v.len())),
            Data::Logical(v) => Some((MI_UINT8, v.len())),
            Data::Char(s) => Some((MI_UTF8, s.len())),
            Data::Cell(_) => None,
        }
    }
}

/// A two-dimensional array: rows x cols values of one class.
#[derive(Debug, Clone, PartialEq)]
pub struct Array {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// The values, column-major (rows x cols of them).
    pub data: Data,
}

impl Array {
    /// A rows x cols array of `data` (checked when it is inserted into a [`MatFile`]).
    pub fn new(rows: usize, cols: usize, data: Data) -> Self {
        Array { rows, cols, data }
    }

    /// A column of values.
    pub fn column(data: Data) -> Self {
        Array::new(data.len(), 1, data)
    }

    /// A char array: 1 x (characters of `text`), or 0 x 0 for an empty text (as MATLAB
    /// stores `''`).
    pub fn text(text: &str) -> Self {
        let n = text.chars().count();
        let rows = usize::from(n > 0);
        Array::new(rows, n, Data::Char(text.to_owned()))
    }

    /// The bytes of this array's `miMATRIX` element, its tag included.
    fn matrix_len(&self, name: &str) -> u64 {
        8 + self.matrix_body_len(name)
    }

    /// The bytes of this array's `miMATRIX` element after its tag.
    fn matrix_body_len(&self, name: &str) -> u64 {
        let flags = element_len(8);
        let dims = element_len(8);
        let name = element_len(name.len());
        let data = match &self.data {
            Data::Cell(cells) => cells.iter().map(|c| c.matrix_len("")).sum(),
            other => other.element().map_or(0, |(_, n)| element_len(n)),
        };
        flags + dims + name + data
    }

    /// Checks the shape, recursively: `Err` says what is wrong.
    fn check(&self) -> Result<(), String> {
        let found = self.data.len();
        if self.rows.checked_mul(self.cols) != Some(found) {
            return Err(format!(
                "{} x {} needs {} values, it has {found}",
                self.rows,
                self.cols,
                self.rows.saturating_mul(self.cols)
            ));
        }
        if i32::try_from(self.rows).is_err() || i32::try_from(self.cols).is_err() {
            return Err(format!(
                "{} x {} is more than 2^31 - 1 rows or columns",
                self.rows, self.cols
            ));
        }
        if let Data::Char(text) = &self.data
            && self.rows > 1
        {
            return Err(format!("a char array of {} rows: {text:?}", self.rows));
        }
        if let Data::Cell(cells) = &self.data {
            for (i, cell) in cells.iter().enumerate() {
                cell.check().map_err(|e| format!("cell {i}: {e}"))?;
            }
        }
        Ok(())
    }

    /// Writes this array's `miMATRIX` element.
    fn write_matrix<W: Write>(&self, w: &mut W, name: &str) -> io::Result<()> {
        let body = u32::try_from(self.matrix_body_len(name))
            .map_err(|_| io::Error::other("a MAT-file variable over 4 GiB"))?;
        w.write_all(&MI_MATRIX.to_le_bytes())?;
        w.write_all(&body.to_le_bytes())?;
        let (class, flags) = self.data.class();
        let mut flag_bytes = [0u8; 8];
        flag_bytes[..4].copy_from_slice(&(u32::from(flags) << 8 | u32::from(class)).to_le_bytes());
        write_element(w, MI_UINT32, 8, |w| w.write_all(&flag_bytes))?;
        write_element(w, MI_INT32, 8, |w| {
            // Checked by `check`: both fit an i32.
            w.write_all(&(self.rows as u32).to_le_bytes())?;
            w.write_all(&(self.cols as u32).to_le_bytes())
        })?;
        write_element(w, MI_INT8, name.len(), |w| w.write_all(name.as_bytes()))?;
        let Some((ty, len)) = self.data.element() else {
            if let Data::Cell(cells) = &self.data {
                for cell in cells {
                    cell.write_matrix(w, "")?;
                }
            }
            return Ok(());
        };
        write_element(w, ty, len, |w| match &self.data {
            Data::Double(v) => v.iter().try_for_each(|x| w.write_all(&x.to_le_bytes())),
            Data::Uint8(v) => w.write_all(v),
            Data::Uint16(v) => v.iter().try_for_each(|x| w.write_all(&x.to_le_bytes())),
            Data::Uint64(v) => v.iter().try_for_each(|x| w.write_all(&x.to_le_bytes())),
            Data::Logical(v) => v.iter().try_for_each(|&x| w.write_all(&[u8::from(x)])),
            Data::Char(s) => w.write_all(s.as_bytes()),
            Data::Cell(_) => Ok(()),
        })
    }
}

/// The bytes a data element of `n` payload bytes takes: 8 in the small format (at most 4
/// bytes), else the tag and the payload padded to 8 bytes.
fn element_len(n: usize) -> u64 {
    if n <= 4 {
        8
    } else {
        8 + (n as u64).div_ceil(8) * 8
    }
}

/// Writes a data element of type `ty` whose payload (`len` bytes) `payload` writes.
fn write_element<W: Write>(
    w: &mut W,
    ty: u32,
    len: usize,
    payload: impl FnOnce(&mut W) -> io::Result<()>,
) -> io::Result<()> {
    if len <= 4 {
        // Small data element format: the length in the upper 16 bits of the type.
        w.write_all(&((len as u32) << 16 | ty).to_le_bytes())?;
        payload(w)?;
        w.write_all(&[0; 4][..4 - len])
    } else {
        let n = u32::try_from(len)
            .map_err(|_| io::Error::other("a MAT-file data element over 4 GiB"))?;
        w.write_all(&ty.to_le_bytes())?;
        w.write_all(&n.to_le_bytes())?;
        payload(w)?;
        w.write_all(&[0; 8][..(8 - len % 8) % 8])
    }
}

/// Why a variable could not be added to a [`MatFile`].
#[derive(Debug, thiserror::Error)]
pub enum MatError {
    /// The name is not a MATLAB identifier.
    #[error(
        "{0:?} is not a MATLAB variable name (a letter, then letters, digits or _, at most 63)"
    )]
    Name(String),
    /// The name is taken.
    #[error("variable {0} added twice")]
    Duplicate(String),
    /// The array's shape does not match its values, or it is too large for the format.
    #[error("variable {name}: {why}")]
    Shape {
        /// The variable.
        name: String,
        /// What is wrong.
        why: String,
    },
    /// The variable is more than the format's 4 GiB per variable.
    #[error(
        "variable {name}: {bytes} bytes, more than a level 5 MAT-file holds per variable (4 GiB)"
    )]
    TooLarge {
        /// The variable.
        name: String,
        /// Its element's size, bytes.
        bytes: u64,
    },
}

/// A MAT-file's variables, in order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MatFile {
    variables: Vec<(String, Array)>,
}

impl MatFile {
    /// An empty file.
    pub fn new() -> Self {
        MatFile::default()
    }

    /// Adds a variable, checking its name, its shape and its size.
    pub fn insert(&mut self, name: &str, array: Array) -> Result<(), MatError> {
        let mut chars = name.chars();
        let valid = chars.next().is_some_and(|c| c.is_ascii_alphabetic())
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
            && name.len() <= MAX_NAME_LEN;
        if !valid {
            return Err(MatError::Name(name.to_owned()));
        }
        if self.get(name).is_some() {
            return Err(MatError::Duplicate(name.to_owned()));
        }
        array.check().map_err(|why| MatError::Shape {
            name: name.to_owned(),
            why,
        })?;
        let bytes = array.matrix_body_len(name);
        if u32::try_from(bytes).is_err() {
            return Err(MatError::TooLarge {
                name: name.to_owned(),
                bytes,
            });
        }
        self.variables.push((name.to_owned(), array));
        Ok(())
    }

    /// The variable called `name`.
    pub fn get(&self, name: &str) -> Option<&Array> {
        self.variables
            .iter()
            .find_map(|(n, a)| (n == name).then_some(a))
    }

    /// The variables' names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.variables.iter().map(|(n, _)| n.as_str())
    }

    /// The file's length, bytes.
    pub fn len_bytes(&self) -> u64 {
        HEADER_LEN as u64
            + self
                .variables
                .iter()
                .map(|(name, array)| array.matrix_len(name))
                .sum::<u64>()
    }

    /// Writes the file. Every error of `w` is returned (nothing is dropped); buffer `w` for
    /// speed (the values are written one by one).
    pub fn write_to<W: Write>(&self, w: &mut W) -> io::Result<()> {
        w.write_all(&header())?;
        for (name, array) in &self.variables {
            array.write_matrix(w, name)?;
        }
        w.flush()
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(usize::try_from(self.len_bytes()).unwrap_or(0));
        // Writing to a Vec cannot fail.
        let _infallible = self.write_to(&mut bytes);
        bytes
    }
}

/// The 128-byte header: descriptive text (no date, so an export is reproducible), no
/// subsystem data, version 0x0100, `IM` (little-endian).
fn header() -> [u8; HEADER_LEN] {
    let mut h = [b' '; HEADER_LEN];
    let text = format!(
        "MATLAB 5.0 MAT-file, Platform: {}, Created by: antenna export {}",
        std::env::consts::OS,
        env!("CARGO_PKG_VERSION")
    );
    let n = text.len().min(116);
    h[..n].copy_from_slice(&text.as_bytes()[..n]);
    h[116..124].fill(0);
    h[124..126].copy_from_slice(&0x0100u16.to_le_bytes());
    h[126..128].copy_from_slice(b"IM");
    h
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The bytes after the header.
    fn body(mat: &MatFile) -> Vec<u8> {
        let bytes = mat.to_bytes();
        assert_eq!(bytes.len() as u64, mat.len_bytes());
        assert_eq!(bytes.len() % 8, 0);
        bytes[HEADER_LEN..].to_vec()
    }

    fn le(words: &[u32]) -> Vec<u8> {
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    #[test]
    fn the_header_says_level_5_little_endian() {
        let bytes = MatFile::new().to_bytes();
        assert_eq!(bytes.len(), HEADER_LEN);
        assert!(bytes.starts_with(b"MATLAB 5.0 MAT-file, Platform: "));
        assert_eq!(&bytes[116..124], &[0; 8]);
        assert_eq!(&bytes[124..], &[0x00, 0x01, b'I', b'M']);
    }

    #[test]
    fn whole_doubles_stay_doubles() {
        // An all-zero double column: class double with miDOUBLE data (matrw wrote miUINT8).
        let mut mat = MatFile::new();
        mat.insert("zeros", Array::column(Data::Double(vec![0.0, 0.0])))
            .unwrap();
        let mut expected = le(&[MI_MATRIX, 72, MI_UINT32, 8, u32::from(MX_DOUBLE), 0]);
        expected.extend(le(&[MI_INT32, 8, 2, 1, MI_INT8, 5]));
        expected.extend(b"zeros\0\0\0");
        expected.extend(le(&[MI_DOUBLE, 16]));
        expected.extend([0u8; 16]);
        assert_eq!(body(&mat), expected);
    }

    #[test]
    fn small_elements_and_the_logical_flag_are_written_as_scipy_writes_them() {
        // scipy.io.savemat({'b': np.array([[True, False]])}) writes exactly these bytes.
        let mut mat = MatFile::new();
        mat.insert("b", Array::new(1, 2, Data::Logical(vec![true, false])))
            .unwrap();
        let expected = le(&[
            MI_MATRIX,
            48,
            MI_UINT32,
            8,
            0x0209,
            0,
            MI_INT32,
            8,
            1,
            2,
            1 << 16 | MI_INT8,
            u32::from(b'b'),
            2 << 16 | MI_UINT8,
            1,
        ]);
        assert_eq!(body(&mat), expected);
    }

    #[test]
    fn integers_text_and_cells() {
        let mut mat = MatFile::new();
        mat.insert("u", Array::new(1, 2, Data::Uint64(vec![1, 2])))
            .unwrap();
        mat.insert("s", Array::text("héllo")).unwrap();
        mat.insert("e", Array::text("")).unwrap();
        let cells = vec![Array::text("k"), Array::text("v")];
        mat.insert("c", Array::new(1, 2, Data::Cell(cells)))
            .unwrap();
        let body = body(&mat);
        // u: as scipy writes np.array([[1, 2]], dtype=np.uint64).
        let mut u = le(&[MI_MATRIX, 64, MI_UINT32, 8, u32::from(MX_UINT64), 0]);
        u.extend(le(&[MI_INT32, 8, 1, 2, 1 << 16 | MI_INT8, u32::from(b'u')]));
        u.extend(le(&[MI_UINT64, 16, 1, 0, 2, 0]));
        assert_eq!(&body[..u.len()], &u[..]);
        // s: 1 x 5 characters, 6 UTF-8 bytes.
        let s = &body[u.len()..];
        assert_eq!(&s[24..40], &le(&[MI_INT32, 8, 1, 5])[..]);
        assert_eq!(&s[48..56], &le(&[MI_UTF8, 6])[..]);
        assert_eq!(&s[56..64], "héllo\0\0".as_bytes());
        // e: 0 x 0 char with an empty data element, as scipy writes ''.
        let e = &s[64..];
        assert_eq!(&e[..8], &le(&[MI_MATRIX, 48])[..]);
        assert_eq!(&e[32..40], &le(&[0, 0])[..]);
        assert_eq!(&e[48..56], &le(&[MI_UTF8, 0])[..]);
        // c: a cell of two char arrays, each a matrix with an empty name.
        let c = &e[56..];
        assert_eq!(&c[8..16], &le(&[MI_UINT32, 8])[..]);
        assert_eq!(c[16], MX_CELL);
        let first = &c[48..];
        assert_eq!(&first[..4], &MI_MATRIX.to_le_bytes());
        assert_eq!(&first[40..48], &le(&[MI_INT8, 0])[..]);
        assert_eq!(c.len() as u64, Array::text("k").matrix_len("") * 2 + 48);
    }

    #[test]
    fn bad_names_and_shapes_are_refused() {
        let mut mat = MatFile::new();
        let one = || Array::column(Data::Double(vec![1.0]));
        for bad in ["", "1x", "a-b", "_a", &"a".repeat(64)] {
            assert!(
                matches!(mat.insert(bad, one()), Err(MatError::Name(_))),
                "{bad}"
            );
        }
        mat.insert("a", one()).unwrap();
        assert!(matches!(
            mat.insert("a", one()),
            Err(MatError::Duplicate(_))
        ));
        let err = mat
            .insert("b", Array::new(2, 2, Data::Uint8(vec![1, 2, 3])))
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "variable b: 2 x 2 needs 4 values, it has 3"
        );
        let cell = Array::new(
            1,
            1,
            Data::Cell(vec![Array::new(1, 2, Data::Uint8(vec![]))]),
        );
        let err = mat.insert("c", cell).unwrap_err().to_string();
        assert!(err.contains("cell 0: 1 x 2 needs 2 values"), "{err}");
        assert_eq!(mat.names().collect::<Vec<_>>(), ["a"]);
    }

    /// A writer that takes `room` bytes, then fails as a full disk does.
    struct Full {
        room: usize,
    }

    impl Write for Full {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if self.room == 0 {
                return Err(io::Error::from_raw_os_error(28));
            }
            let n = buf.len().min(self.room);
            self.room -= n;
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_write_error_is_returned_wherever_it_happens() {
        let mut mat = MatFile::new();
        mat.insert("x", Array::column(Data::Double(vec![0.5; 100])))
            .unwrap();
        mat.insert("t", Array::text("text")).unwrap();
        let len = mat.len_bytes() as usize;
        for room in [0, 5, 127, 128, 200, len - 1] {
            let err = mat.write_to(&mut Full { room }).unwrap_err();
            assert_eq!(err.raw_os_error(), Some(28), "{room}");
        }
        mat.write_to(&mut Full { room: len }).unwrap();
    }
}
