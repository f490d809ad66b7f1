//! A glTF's bytes: its buffers (the GLB's binary chunk, `data:` URIs, files beside the document) and
//! the accessors that read them, every offset, length and count checked before anything is
//! allocated or read.

use crate::error::{GltfPart, InputError};
use base64::Engine;
use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use std::path::{Component, Path, PathBuf};

/// Where a document's external files are read from: its own folder and below, or nowhere (a page
/// given the file's bytes alone).
#[derive(Clone, Copy, Debug)]
pub enum Files<'a> {
    /// This folder and below.
    Folder(&'a Path),
    /// Nowhere: the document's own bytes and `data:` URIs only.
    None,
}

/// The most elements an accessor may have: a render takes at most 2^24 - 1 primitives, so no
/// attribute of one needs more.
pub(crate) const MAX_ACCESSOR_COUNT: u64 = 1 << 24;
/// The largest image file read.
pub(crate) const MAX_IMAGE_BYTES: u64 = 256 << 20;

/// The bytes an external or `data:` URI names. `cap` bounds what is read; `part` (a buffer or an
/// image) holds the URI.
pub(crate) fn read_uri(uri: &str, files: Files, cap: u64, part: GltfPart) -> Result<Vec<u8>, InputError> {
    read_uri_bytes(uri, files, cap).map_err(|e| e.within(part))
}

fn read_uri_bytes(uri: &str, files: Files, cap: u64) -> Result<Vec<u8>, InputError> {
    let fail = |message: String| Err(InputError::new(message));
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return fail("data URI without a comma".into());
        };
        if !header.ends_with(";base64") {
            return fail("only base64 data URIs are read".into());
        }
        // Base64 grows data by 4/3: a payload this long cannot decode to more than the cap.
        if payload.len() as u64 / 4 * 3 > cap + 3 {
            return fail(format!("data URI longer than the {cap} bytes it may hold"));
        }
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(payload.trim_end())
            .map_err(|e| InputError::new(format!("data URI is not base64: {e}")))?;
        if bytes.len() as u64 > cap {
            return fail(format!(
                "data URI holds {} bytes, more than the {cap} it may",
                bytes.len()
            ));
        }
        return Ok(bytes);
    }
    let relative = relative_path(uri)?;
    let Files::Folder(folder) = files else {
        return fail(format!(
            "external file '{}' cannot be read here (give a .glb, or a .gltf with data: URIs)",
            crate::error::quoted(uri)
        ));
    };
    let path = folder.join(&relative);
    // Links may point anywhere: the file must still lie in the document's folder once resolved.
    let (Ok(real_folder), Ok(real_path)) = (folder.canonicalize(), path.canonicalize()) else {
        return fail(format!("cannot read '{}': no such file", relative.display()));
    };
    if !real_path.starts_with(&real_folder) {
        return fail(format!("'{}' lies outside the glTF's folder", relative.display()));
    }
    crate::input::read_regular(&real_path, "file", cap).map_err(|e| InputError::new(e.message))
}

/// A URI reference as a path below the document's folder: percent-escapes decoded, and refused
/// when absolute, with a scheme, or climbing out with `..`.
fn relative_path(uri: &str) -> Result<PathBuf, InputError> {
    let decoded = percent_decode(uri)
        .ok_or_else(|| InputError::new(format!("URI '{}' is not valid UTF-8", crate::error::quoted(uri))))?;
    let shown = crate::error::quoted(&decoded);
    if decoded.is_empty() {
        return Err(InputError::new("empty URI"));
    }
    if decoded.contains(':') || decoded.starts_with(['/', '\\']) {
        return Err(InputError::new(format!(
            "URI '{shown}' is absolute: only files beside the glTF are read"
        )));
    }
    let path = PathBuf::from(decoded.replace('\\', "/"));
    if path
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
    {
        return Err(InputError::new(format!("URI '{shown}' leaves the glTF's folder")));
    }
    Ok(path)
}

fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && let Some(value) = text.get(i + 1..i + 3).and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(value);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Every buffer's bytes, by index: each at least its `byteLength` long, and cut to it.
pub(crate) fn load_buffers(root: &json::Root, blob: Option<Vec<u8>>, files: Files) -> Result<Vec<Vec<u8>>, InputError> {
    let mut blob = blob;
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (index, buffer) in root.buffers.iter().enumerate() {
        let fault = |message: String| InputError::in_gltf(GltfPart::Buffer(index), message);
        let length = buffer.byte_length.0;
        if length > crate::input::MAX_MODEL_BYTES {
            return Err(fault(format!("byteLength {length} is more than a model may hold")));
        }
        let mut bytes = match (&buffer.uri, index) {
            (Some(uri), _) => read_uri(uri, files, length, GltfPart::Buffer(index))?,
            (None, 0) => blob
                .take()
                .ok_or_else(|| fault("no uri, and the file has no binary chunk".into()))?,
            (None, _) => return Err(fault("no uri (only buffer 0 may be a GLB's binary chunk)".into())),
        };
        if (bytes.len() as u64) < length {
            return Err(fault(format!(
                "{} bytes, less than its byteLength {length}",
                bytes.len()
            )));
        }
        bytes.truncate(length as usize);
        buffers.push(bytes);
    }
    Ok(buffers)
}

/// The bytes of buffer view `index`, checked against its buffer.
pub(crate) fn view_bytes<'a>(root: &json::Root, buffers: &'a [Vec<u8>], index: usize) -> Result<&'a [u8], InputError> {
    let view = root
        .buffer_views
        .get(index)
        .ok_or_else(|| InputError::new(format!("buffer view {index} does not exist")))?;
    let fail = |message: String| InputError::in_gltf(GltfPart::BufferView(index), message);
    let buffer = buffers
        .get(view.buffer.value())
        .ok_or_else(|| fail(format!("buffer {} does not exist", view.buffer.value())))?;
    let offset = view.byte_offset.map_or(0, |o| o.0);
    let length = view.byte_length.0;
    let end = offset.checked_add(length).filter(|&end| end <= buffer.len() as u64);
    let Some(end) = end else {
        return Err(fail(format!(
            "bytes {offset}..{} reach past buffer {} ({} bytes)",
            offset.saturating_add(length),
            view.buffer.value(),
            buffer.len()
        )));
    };
    Ok(&buffer[offset as usize..end as usize])
}

fn component_size(component: ComponentType) -> usize {
    match component {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// One component at `bytes[0..]` as f32: normalized integers to [0, 1] or [-1, 1] (glTF's rule),
/// other integers as their value.
fn component(bytes: &[u8], component: ComponentType, normalized: bool) -> f32 {
    match component {
        ComponentType::F32 => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        ComponentType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f32,
        ComponentType::U8 if normalized => bytes[0] as f32 / 255.0,
        ComponentType::U8 => bytes[0] as f32,
        ComponentType::I8 if normalized => (bytes[0] as i8 as f32 / 127.0).max(-1.0),
        ComponentType::I8 => bytes[0] as i8 as f32,
        ComponentType::U16 => {
            let value = u16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized { value / 65535.0 } else { value }
        }
        ComponentType::I16 => {
            let value = i16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized { (value / 32767.0).max(-1.0) } else { value }
        }
    }
}

/// An accessor and its component and element types, by index.
pub(crate) fn lookup(root: &json::Root, index: usize) -> Result<(&json::Accessor, ComponentType, Type), InputError> {
    let accessor = root
        .accessors
        .get(index)
        .ok_or_else(|| InputError::new(format!("accessor {index} does not exist")))?;
    let (component_type, type_) =
        accessor_types(accessor).ok_or_else(|| InputError::in_gltf(GltfPart::Accessor(index), "invalid type"))?;
    Ok((accessor, component_type, type_))
}

/// Where an accessor's elements lie in its buffer view: checked to hold them all.
struct Elements<'a> {
    bytes: &'a [u8],
    offset: usize,
    stride: usize,
}

impl<'a> Elements<'a> {
    /// The elements of `accessor`, `count` of `element_size` bytes; `None` where it has no view
    /// (its elements are zeros, before any sparse substitution).
    fn of(
        root: &json::Root,
        buffers: &'a [Vec<u8>],
        accessor: &json::Accessor,
        element_size: usize,
        count: usize,
    ) -> Result<Option<Self>, InputError> {
        let Some(view) = accessor.buffer_view else {
            // Zeros cost memory that no byte of the file pays for: at most twice the buffers' size.
            let paid = 2 * buffers.iter().map(|b| b.len() as u64).sum::<u64>();
            if (count * element_size) as u64 > paid.max(1 << 20) {
                return Err(InputError::new(format!(
                    "{count} elements without a buffer view: more than twice the file's buffers"
                )));
            }
            return Ok(None);
        };
        let bytes = view_bytes(root, buffers, view.value())?;
        let stride = element_stride(root, view.value(), element_size);
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let offset = usize::try_from(offset)
            .map_err(|_| InputError::new(format!("byteOffset {offset} is beyond any buffer")))?;
        check_span(bytes.len(), offset, stride, element_size, count)?;
        Ok(Some(Self { bytes, offset, stride }))
    }

    /// Element `e`'s bytes, and what follows them.
    fn at(&self, e: usize) -> &'a [u8] {
        &self.bytes[self.offset + e * self.stride..]
    }
}

/// An accessor's count, refused above `limit` before anything is allocated.
fn bounded_count(accessor: &json::Accessor, limit: u64, what: &str) -> Result<usize, InputError> {
    let count = accessor.count.0;
    if count > limit {
        return Err(InputError::new(format!(
            "count {count} is more than the {limit} {what}"
        )));
    }
    Ok(count as usize)
}

/// An accessor's elements as f32s, one after another (as many to an element as its type has);
/// `types` lists the element types the caller takes. Sparse substitutions are applied. Errors lie
/// within the accessor.
pub(crate) fn read_floats(
    root: &json::Root,
    buffers: &[Vec<u8>],
    index: usize,
    types: &[Type],
) -> Result<Vec<f32>, InputError> {
    let (accessor, component_type, type_) = lookup(root, index)?;
    floats_of(root, buffers, accessor, (component_type, type_), types).map_err(|e| e.within(GltfPart::Accessor(index)))
}

fn floats_of(
    root: &json::Root,
    buffers: &[Vec<u8>],
    accessor: &json::Accessor,
    (component_type, type_): (ComponentType, Type),
    types: &[Type],
) -> Result<Vec<f32>, InputError> {
    if !types.contains(&type_) {
        return Err(InputError::new(format!("type {type_:?} where {types:?} is expected")));
    }
    let width = type_.multiplicity();
    let count = bounded_count(accessor, MAX_ACCESSOR_COUNT, "elements an accessor may have")?;
    let size = component_size(component_type);
    let elements = Elements::of(root, buffers, accessor, width * size, count)?;
    let mut values = vec![0.0f32; count * width];
    if let Some(elements) = elements {
        for (e, element) in values.chunks_exact_mut(width).enumerate() {
            let bytes = elements.at(e);
            for (c, value) in element.iter_mut().enumerate() {
                *value = component(&bytes[c * size..], component_type, accessor.normalized);
            }
        }
    }
    if let Some(sparse) = &accessor.sparse {
        let substitutes = sparse.count.0;
        if substitutes > count as u64 {
            return Err(InputError::new(format!(
                "sparse count {substitutes} is more than the count {count}"
            )));
        }
        let substitutes = substitutes as usize;
        let indices = sparse_indices(root, buffers, &sparse.indices, substitutes)
            .map_err(|e| e.within_named("sparse indices"))?;
        let bytes = view_bytes(root, buffers, sparse.values.buffer_view.value())?;
        let offset = sparse.values.byte_offset.0 as usize;
        check_span(bytes.len(), offset, width * size, width * size, substitutes)
            .map_err(|e| e.within_named("sparse values"))?;
        for (k, &target) in indices.iter().enumerate() {
            if target as usize >= count {
                return Err(InputError::new(format!(
                    "sparse index {target} out of range ({count} elements)"
                )));
            }
            for c in 0..width {
                let at = offset + (k * width + c) * size;
                values[target as usize * width + c] = component(&bytes[at..], component_type, accessor.normalized);
            }
        }
    }
    Ok(values)
}

fn accessor_types(accessor: &json::Accessor) -> Option<(ComponentType, Type)> {
    let json::validation::Checked::Valid(generic) = accessor.component_type else {
        return None;
    };
    let json::validation::Checked::Valid(type_) = accessor.type_ else {
        return None;
    };
    Some((generic.0, type_))
}

/// The distance between elements in view `view`: its byteStride, or the element size when packed.
fn element_stride(root: &json::Root, view: usize, element_size: usize) -> usize {
    root.buffer_views
        .get(view)
        .and_then(|v| v.byte_stride)
        .map_or(element_size, |s| s.0)
}

/// Whether `count` elements of `element_size` bytes, `stride` apart from `offset`, fit in `length`.
fn check_span(
    length: usize,
    offset: usize,
    stride: usize,
    element_size: usize,
    count: usize,
) -> Result<(), InputError> {
    if count == 0 {
        return Ok(());
    }
    if stride < element_size {
        return Err(InputError::new(format!(
            "byteStride {stride} is less than the element's {element_size} bytes"
        )));
    }
    let end = (count as u64 - 1) * stride as u64 + element_size as u64 + offset as u64;
    if end > length as u64 {
        return Err(InputError::new(format!(
            "{count} elements of {element_size} bytes, {stride} apart from byte {offset}, need {end} bytes; its buffer view has {length}"
        )));
    }
    Ok(())
}

fn sparse_indices(
    root: &json::Root,
    buffers: &[Vec<u8>],
    indices: &json::accessor::sparse::Indices,
    count: usize,
) -> Result<Vec<u32>, InputError> {
    let json::validation::Checked::Valid(kind) = indices.component_type else {
        return Err(InputError::new("invalid component type"));
    };
    let bytes = view_bytes(root, buffers, indices.buffer_view.value())?;
    let size = component_size(kind.0);
    let offset = indices.byte_offset.0 as usize;
    check_span(bytes.len(), offset, size, size, count)?;
    Ok((0..count)
        .map(|k| component(&bytes[offset + k * size..], kind.0, false) as u32)
        .collect())
}

/// An index accessor's values (unsigned bytes, shorts or ints), each below `vertex_count`.
pub(crate) fn read_indices(
    root: &json::Root,
    buffers: &[Vec<u8>],
    index: usize,
    vertex_count: usize,
) -> Result<Vec<u32>, InputError> {
    let (accessor, component_type, type_) = lookup(root, index)?;
    indices_of(root, buffers, accessor, (component_type, type_), vertex_count)
        .map_err(|e| e.within(GltfPart::Accessor(index)))
}

fn indices_of(
    root: &json::Root,
    buffers: &[Vec<u8>],
    accessor: &json::Accessor,
    (component_type, type_): (ComponentType, Type),
    vertex_count: usize,
) -> Result<Vec<u32>, InputError> {
    if type_ != Type::Scalar
        || !matches!(
            component_type,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        )
    {
        return Err(InputError::new(format!(
            "indices must be unsigned scalars (got {component_type:?} {type_:?})"
        )));
    }
    if accessor.sparse.is_some() {
        return Err(InputError::new("sparse index accessors are not read"));
    }
    let count = bounded_count(accessor, MAX_ACCESSOR_COUNT * 3, "indices of a render's triangles")?;
    let size = component_size(component_type);
    let elements = Elements::of(root, buffers, accessor, size, count)?;
    // Read as integers: f32 is not exact for every u32.
    let mut values = vec![0u32; count];
    if let Some(elements) = elements {
        for (e, value) in values.iter_mut().enumerate() {
            let b = elements.at(e);
            *value = match component_type {
                ComponentType::U8 => b[0] as u32,
                ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            };
        }
    }
    if let Some((k, &bad)) = values.iter().enumerate().find(|&(_, &v)| v as usize >= vertex_count) {
        return Err(InputError::new(format!(
            "index {k} is {bad}, out of range ({vertex_count} vertices)"
        )));
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_stay_in_the_folder() {
        assert_eq!(relative_path("a%20b.bin").unwrap(), PathBuf::from("a b.bin"));
        assert_eq!(relative_path("sub/./c.bin").unwrap(), PathBuf::from("sub/c.bin"));
        for bad in [
            "../x.bin",
            "sub/../../x.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "C:\\x.bin",
            "%2e%2e/x",
            "",
        ] {
            assert!(relative_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn data_uris_decode_and_are_bounded() {
        let files = Files::None;
        assert_eq!(
            read_uri(
                "data:application/octet-stream;base64,AAEC",
                files,
                3,
                GltfPart::Buffer(0)
            )
            .unwrap(),
            vec![0, 1, 2]
        );
        assert!(
            read_uri(
                "data:application/octet-stream;base64,AAECAAEC",
                files,
                3,
                GltfPart::Buffer(0)
            )
            .is_err()
        );
        assert!(
            read_uri("data:text/plain,hello", files, 10, GltfPart::Buffer(0))
                .unwrap_err()
                .message
                .contains("base64")
        );
        let external = read_uri("x.bin", files, 10, GltfPart::Buffer(0))
            .unwrap_err()
            .to_string();
        assert!(
            external.starts_with("buffer 0: external file 'x.bin' cannot be read here"),
            "{external}"
        );
    }

    #[test]
    fn spans_are_checked_before_reading() {
        assert!(check_span(12, 0, 12, 12, 1).is_ok());
        assert!(check_span(24, 4, 12, 12, 2).is_err());
        assert!(check_span(100, 0, 4, 12, 2).unwrap_err().message.contains("byteStride"));
        // A count of 2^31 with a stride of 2^31 does not overflow.
        assert!(check_span(100, 0, 1 << 31, 12, 1 << 31).is_err());
    }

    #[test]
    fn normalized_components_follow_the_spec() {
        assert_eq!(component(&[255], ComponentType::U8, true), 1.0);
        assert_eq!(component(&[0x80], ComponentType::I8, true), -1.0);
        assert_eq!(component(&[0xff, 0x7f], ComponentType::I16, true), 1.0);
        assert_eq!(component(&[7, 0], ComponentType::U16, false), 7.0);
    }
}
