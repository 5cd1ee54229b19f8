//! A ZIP archive with its entries stored uncompressed (PKWARE's APPNOTE.TXT 6.3, §4.3: local
//! file headers, the central directory, its end record): the container of an FMI unit (FMI 3.0
//! §2.5). Stored entries keep the writer small; the unit's largest file, the shared library,
//! would compress to about a third.

/// The files of an archive, written in the order added.
#[derive(Default)]
pub struct Archive {
    entries: Vec<(String, Vec<u8>)>,
}

/// 1980-01-01 00:00 in MS-DOS time and date, for every entry: the archive depends on its
/// contents alone.
const DOS_TIME: u16 = 0;
const DOS_DATE: u16 = 1 << 5 | 1;

impl Archive {
    /// Adds a file at `path` (separated by `/`); folders are implied by the paths.
    pub fn add(&mut self, path: &str, contents: Vec<u8>) {
        self.entries.push((path.to_string(), contents));
    }

    /// The archive's bytes; an error when it would need ZIP64 (4 GiB, 65,535 entries).
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        let mut central = Vec::new();
        if self.entries.len() > usize::from(u16::MAX) {
            return Err("more than 65,535 files in one unit".to_string());
        }
        for (path, contents) in &self.entries {
            let offset = u32::try_from(out.len()).map_err(|_| too_large())?;
            let size = u32::try_from(contents.len()).map_err(|_| too_large())?;
            let name = path.as_bytes();
            let crc = crc32fast::hash(contents);
            // Local file header (§4.3.7): version 2.0, flags 0 (bit 11 where the name is UTF-8),
            // method 0 (stored).
            let flags: u16 = if path.is_ascii() { 0 } else { 1 << 11 };
            let fields = |out: &mut Vec<u8>| {
                put16(out, 20);
                put16(out, flags);
                put16(out, 0);
                put16(out, DOS_TIME);
                put16(out, DOS_DATE);
                put32(out, crc);
                put32(out, size);
                put32(out, size);
                put16(out, name.len() as u16);
                put16(out, 0);
            };
            put32(&mut out, 0x0403_4b50);
            fields(&mut out);
            out.extend_from_slice(name);
            out.extend_from_slice(contents);
            // Central directory header (§4.3.12): made by version 2.0 on Unix (3), then the
            // local header's fields, no comment, disk 0, attributes (a regular file, rw-r--r--).
            put32(&mut central, 0x0201_4b50);
            put16(&mut central, 3 << 8 | 20);
            fields(&mut central);
            put16(&mut central, 0);
            put16(&mut central, 0);
            put16(&mut central, 0);
            put32(&mut central, 0o100644 << 16);
            put32(&mut central, offset);
            central.extend_from_slice(name);
        }
        let start = u32::try_from(out.len()).map_err(|_| too_large())?;
        let length = u32::try_from(central.len()).map_err(|_| too_large())?;
        out.extend_from_slice(&central);
        // End of central directory record (§4.3.16).
        let count = self.entries.len() as u16;
        put32(&mut out, 0x0605_4b50);
        put16(&mut out, 0);
        put16(&mut out, 0);
        put16(&mut out, count);
        put16(&mut out, count);
        put32(&mut out, length);
        put32(&mut out, start);
        put16(&mut out, 0);
        Ok(out)
    }
}

fn too_large() -> String {
    "the unit's files exceed 4 GiB, the limit of a ZIP archive without ZIP64".to_string()
}

fn put16(out: &mut Vec<u8>, value: u16) {
    out.extend_from_slice(&value.to_le_bytes());
}

fn put32(out: &mut Vec<u8>, value: u32) {
    out.extend_from_slice(&value.to_le_bytes());
}
