#pragma once
/// Image files without OpenImageIO (which costs ~0.45 s of start-up per process):
/// PNG (8/16-bit, gray, gray+alpha, RGB, RGBA) through libpng, JPEG through libjpeg,
/// OpenEXR (half/float, any channels, multi-layer) through OpenEXR.
///
/// Values: 8-bit and 16-bit files read as value / 255 or / 65535 (no colour-space
/// conversion: tdf treats texture files as plain numbers, as the reference does).
/// Writers quantise by truncation by default (`floor(x*255)`, the reference's `astype(uint8)`,
/// spec 13.20) or by rounding; values are clamped to [0, 1] first.
/// All writers write atomically (temporary name, then rename).
#include <tdf/core/image.h>

#include <map>
#include <string>
#include <vector>

namespace tdf {

/// Largest image the readers accept: each side at most kMaxImageSide pixels and at most
/// kMaxImagePixels in all (16384 x 16384). A header claiming more, or claiming far more pixels
/// than the file's size can encode (more than 4096 decoded bytes per file byte), is an error
/// naming the file, raised before any pixel memory is allocated.
inline constexpr int kMaxImageSide = 65536;
inline constexpr long long kMaxImagePixels = 16384LL * 16384LL;

/// Reads a PNG, JPEG or EXR file (chosen by content, not extension). For EXR files the
/// channels are returned in the file's order (see read_exr_layers for names).
/// Throws tdf::Error naming the file for missing, truncated or unsupported files.
Image read_image(const std::string& path);

/// Decodes a PNG or JPEG held in memory (e.g. embedded in a .glb), with the same value
/// conventions and size limits as read_image; `where` names it in errors.
Image decode_image(const std::string& bytes, const std::string& where);

enum class Quantize { Truncate, Round };

/// Key-value text stored with an image: PNG tEXt chunks (keys of 1-79 Latin-1 characters) or
/// EXR string attributes. tdf uses keys such as "tdf:mm_per_pixel" (docs/conventions.md).
using ImageMetadata = std::map<std::string, std::string>;

/// read_image that also returns the file's text metadata (PNG tEXt/zTXt/iTXt chunks, EXR
/// string attributes; JPEG has none). Other attributes are not returned.
Image read_image(const std::string& path, ImageMetadata& metadata);

/// Writes 1-4 channels as an 8- or 16-bit PNG. Every writer refuses a name whose extension
/// says another format (`-o map.jpg` never receives PNG bytes).
void write_png(const std::string& path, const Image& image, int bits = 8,
               Quantize quantize = Quantize::Truncate);
/// write_png with text metadata, stored as uncompressed tEXt chunks before the pixels.
void write_png(const std::string& path, const Image& image, const ImageMetadata& metadata, int bits = 8,
               Quantize quantize = Quantize::Truncate);

/// Writes 1 (grey) or 3 (RGB) channels as a baseline JPEG of the given quality (1-100);
/// 4 channels drop the alpha. Values are clamped to [0, 1] and rounded.
void write_jpeg(const std::string& path, const Image& image, int quality = 95);

/// Writes `image` in the format its name says: .png (8-bit, or `png_bits`), .jpg/.jpeg, .exr
/// (float). Any other extension is an error naming the file.
void write_image(const std::string& path, const Image& image, int png_bits = 8,
                 Quantize quantize = Quantize::Truncate);

/// Throws tdf::Error unless `path` ends in one of `extensions` (lower-case, with the dot), e.g.
/// check_output_extension(path, {".png", ".exr"}, "--diff").
void check_output_extension(const std::string& path, const std::vector<std::string>& extensions,
                            const std::string& what);

/// One named group of channels in a multi-layer EXR: layer "albedo" with channel names
/// {"R","G","B"} is stored as channels "albedo.R", "albedo.G", "albedo.B". An empty layer
/// name stores bare channel names.
struct ExrLayer {
    std::string name;
    std::vector<std::string> channel_names;
    Image image;
};

enum class ExrPixelType { Half, Float };

/// Writes layers of equal size into one EXR (ZIP compression). Channel names are written in
/// the order given; OpenEXR sorts them alphabetically in the file.
void write_exr(const std::string& path, const std::vector<ExrLayer>& layers,
               ExrPixelType type = ExrPixelType::Float);
/// Convenience: one unnamed layer with R,G,B,A / Y names chosen by channel count.
void write_exr(const std::string& path, const Image& image, ExrPixelType type = ExrPixelType::Float);
/// write_exr with text metadata, stored as string attributes of the header.
void write_exr(const std::string& path, const Image& image, const ImageMetadata& metadata,
               ExrPixelType type = ExrPixelType::Float);

/// Reads every channel of an EXR as float, grouped by layer (the text before the last '.').
/// `metadata`, when given, receives the header's string attributes.
std::vector<ExrLayer> read_exr_layers(const std::string& path, ImageMetadata* metadata = nullptr);

/// Lower-cased extension with the dot, e.g. ".png".
std::string lower_extension(const std::string& path);

}  // namespace tdf
