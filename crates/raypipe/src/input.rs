//! Reading the files users name: regular files only (a FIFO, `/dev/zero` or a link to a device would
//! block or never end), and never more bytes than a cap, checked before and while reading.

use crate::error::InputError;
use std::io::Read;
use std::path::Path;

/// The largest scene file read: far past any hand-written scene.
pub(crate) const MAX_SCENE_BYTES: u64 = 16 << 20;
/// The largest model file read: a mesh far past what a render takes.
pub(crate) const MAX_MODEL_BYTES: u64 = 4 << 30;

/// How much of a file is read first, so that a format can refuse it by its header before the
/// rest is read: far more than any header of the formats read.
pub(crate) const HEAD_BYTES: usize = 64 << 10;

/// The bytes of the regular file at `path` (links followed), at most `cap` of them; `what` names
/// the file in messages ("scene file", "model file").
pub(crate) fn read_regular(path: &Path, what: &str, cap: u64) -> Result<Vec<u8>, InputError> {
    read_regular_after_head(path, what, cap, |_, _| Ok(()))
}

/// [`read_regular`], with the first [`HEAD_BYTES`] (or the whole file, if shorter) shown to
/// `check_head` before the rest is read: a file that is not of its format (a gigabyte of zeros
/// named `.ply`) costs a header's read, not its size in memory. `check_head` is told whether it
/// sees the whole file.
pub(crate) fn read_regular_after_head(
    path: &Path,
    what: &str,
    cap: u64,
    check_head: impl FnOnce(&[u8], bool) -> Result<(), InputError>,
) -> Result<Vec<u8>, InputError> {
    let fail = |message: String| InputError::new(message).in_origin(path.display().to_string());
    let metadata = std::fs::metadata(path).map_err(|e| fail(format!("cannot read {what}: {e}")))?;
    if !metadata.is_file() {
        return Err(fail(format!("cannot read {what}: not a regular file")));
    }
    if metadata.len() > cap {
        return Err(fail(format!(
            "cannot read {what}: {} bytes, more than the {cap} read",
            metadata.len()
        )));
    }
    let file = std::fs::File::open(path).map_err(|e| fail(format!("cannot read {what}: {e}")))?;
    // The file may grow while it is read: the cap holds for what is read, not only for its size.
    let mut reader = file.take(cap + 1);
    let mut bytes = Vec::with_capacity((metadata.len() as usize).min(HEAD_BYTES));
    (&mut reader)
        .take(HEAD_BYTES as u64)
        .read_to_end(&mut bytes)
        .map_err(|e| fail(format!("cannot read {what}: {e}")))?;
    let whole = bytes.len() < HEAD_BYTES;
    check_head(&bytes, whole).map_err(|e| e.in_origin(path.display().to_string()))?;
    if !whole {
        bytes.reserve((metadata.len() as usize).saturating_sub(bytes.len()));
        reader
            .read_to_end(&mut bytes)
            .map_err(|e| fail(format!("cannot read {what}: {e}")))?;
    }
    if bytes.len() as u64 > cap {
        return Err(fail(format!("cannot read {what}: more than the {cap} bytes read")));
    }
    Ok(bytes)
}
