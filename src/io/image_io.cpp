#include <tdf/io/image_io.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <ImfChannelList.h>
#include <Imath/half.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfCompression.h>
#include <ImfStringAttribute.h>
#include <Iex.h>
#include <ImfThreading.h>
#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

namespace tdf {

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

namespace {
// OpenEXR compresses and decompresses the blocks of scan lines on its own thread pool, sized to
// the threads tdf's loops may use (ThreadLimit): the blocks' bytes do not depend on it, so files
// are the same on any thread count.
int exr_threads() {
    const int threads = std::max(1, ThreadLimit::current());
    if (Imf::globalThreadCount() != threads) Imf::setGlobalThreadCount(threads);
    return threads;
}
}  // namespace

namespace {

struct FileCloser {
    void operator()(std::FILE* f) const {
        if (f) std::fclose(f);
    }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

FilePtr open_file(const std::string& path, const char* mode) {
    FilePtr f(std::fopen(path.c_str(), mode));
    if (!f) throw_error("cannot open '{}': {}", path, std::strerror(errno));
    return f;
}

// Decoded images are checked against kMaxImageSide / kMaxImagePixels and against the file size
// before any pixel buffer is allocated: a 60-byte PNG header may claim 200000 x 200000 pixels.
// The codecs' densest encodings stay below ~2000 decoded bytes per file byte (DEFLATE's limit
// is 1032:1; a JPEG block costs at least one bit per 64 samples; EXR's PIZ run codes, counted
// in half-float bytes, about 2000:1), so a header claiming more than 4096:1 is a truncated,
// corrupt or hostile file and is refused before it costs memory.
constexpr double kMaxDecodedBytesPerFileByte = 4096.0;

std::uintmax_t file_size_or_zero(const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    return ec ? 0 : size;
}

// `decoded_bytes`: the size of the codec's decoded stream (PNG: filtered rows, JPEG: samples,
// EXR: half-float samples).
void check_image_size(const std::string& path, std::uint64_t file_size, const char* format,
                      std::uint64_t width, std::uint64_t height, double decoded_bytes) {
    if (width == 0 || height == 0)
        throw_error("cannot read {} '{}': the image is empty ({}x{})", format, path, width, height);
    if (width > std::uint64_t(kMaxImageSide) || height > std::uint64_t(kMaxImageSide) ||
        width * height > std::uint64_t(kMaxImagePixels))
        throw_error("cannot read {} '{}': {}x{} pixels is over the limit ({} per side, {} in all)",
                    format,
                    path,
                    width,
                    height,
                    kMaxImageSide,
                    kMaxImagePixels);
    const double file = double(file_size);
    if (decoded_bytes > kMaxDecodedBytesPerFileByte * file + 65536.0)
        throw_error(
            "cannot read {} '{}': the header claims {}x{} pixels but the file has only {} bytes "
            "(truncated or corrupt)",
            format,
            path,
            width,
            height,
            std::uint64_t(file));
}

// ---- PNG -------------------------------------------------------------------------------------

struct PngErrorContext {
    std::string path;
    std::string message;
};

void png_error_handler(png_structp png, png_const_charp message) {
    auto* context = static_cast<PngErrorContext*>(png_get_error_ptr(png));
    context->message = message;
    png_longjmp(png, 1);
}
void png_warning_handler(png_structp, png_const_charp) {}

// `file` holds the image (a file or memory); `path` names it in messages.
// Walks the chunk headers before libpng does: a chunk cannot hold more bytes than the file has
// left, and libpng allocates what a text chunk's header claims (1.5 GB from a 100-byte file,
// found by fuzzing). Leaves the file where it was.
void check_png_chunks(std::FILE* file, const std::string& path, std::uint64_t file_size) {
    const long start = std::ftell(file);
    std::uint64_t offset = 8;  // the signature
    unsigned char header[8];
    while (offset + 8 <= file_size && std::fseek(file, long(offset), SEEK_SET) == 0 &&
           std::fread(header, 1, 8, file) == 8) {
        const std::uint64_t length = (std::uint64_t(header[0]) << 24) | (std::uint64_t(header[1]) << 16) |
                                     (std::uint64_t(header[2]) << 8) | std::uint64_t(header[3]);
        if (offset + 12 + length > file_size)
            throw_error("cannot read PNG '{}': a '{:.4s}' chunk at byte {} claims {} bytes, the file has {} left",
                        path, reinterpret_cast<const char*>(header + 4), offset, length, file_size - offset - 8);
        if (std::memcmp(header + 4, "IEND", 4) == 0) break;
        offset += 12 + length;
    }
    std::fseek(file, start, SEEK_SET);
}

// The decoded rows of a PNG, filled by decode_png.
struct PngPixels {
    png_uint_32 width = 0, height = 0;
    int channels = 0, bit_depth = 0;
    std::vector<unsigned char> buffer;
    std::vector<png_bytep> rows;
};

// Every libpng call that can fail, under one setjmp. The function owns no object with a
// destructor (those live in the caller), so png_longjmp skips none and clobbers nothing that
// is read afterwards (gcc's -Wclobbered fired on read_png's strings at -O1). Returns false on a
// libpng error (the message is in the error context); a size over the limits throws.
bool decode_png(png_structp png, png_infop info, std::FILE* file, const std::string& path,
                std::uint64_t file_size, PngPixels* pixels) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_read_info(png, info);
    pixels->width = png_get_image_width(png, info);
    pixels->height = png_get_image_height(png, info);
    const int color_type = png_get_color_type(png, info);
    const int bit_depth = png_get_bit_depth(png, info);
    check_image_size(path, file_size, "PNG", pixels->width, pixels->height,
                     double(png_get_rowbytes(png, info) + 1) * double(pixels->height));
    if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    if (bit_depth == 16) png_set_swap(png);  // little-endian host order
    png_read_update_info(png, info);
    pixels->channels = png_get_channels(png, info);
    pixels->bit_depth = png_get_bit_depth(png, info);
    const std::size_t row_bytes = png_get_rowbytes(png, info);
    pixels->buffer.resize(row_bytes * pixels->height);
    pixels->rows.resize(pixels->height);
    for (png_uint_32 y = 0; y < pixels->height; ++y) pixels->rows[y] = pixels->buffer.data() + y * row_bytes;
    png_read_image(png, pixels->rows.data());
    png_read_end(png, info);  // `info` also collects text chunks that follow the pixels
    return true;
}

Image read_png(std::FILE* file, const std::string& path, std::uint64_t file_size, ImageMetadata* metadata) {
    check_png_chunks(file, path, file_size);
    PngErrorContext context{path, {}};
    struct ReadStruct {
        png_structp png;
        png_infop info;
        ~ReadStruct() { png_destroy_read_struct(&png, &info, nullptr); }
    } read{png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, png_error_handler, png_warning_handler),
           nullptr};
    read.info = png_create_info_struct(read.png);
    PngPixels pixels;
    if (!decode_png(read.png, read.info, file, path, file_size, &pixels))
        throw_error("cannot read PNG '{}': {}", path, context.message);
    if (metadata) {
        png_textp text = nullptr;
        const int count = png_get_text(read.png, read.info, &text, nullptr);
        for (int i = 0; i < count; ++i)
            (*metadata)[text[i].key] = text[i].text ? std::string(text[i].text) : std::string();
    }

    Image image(int(pixels.width), int(pixels.height), pixels.channels);
    float* out = image.data();
    const std::size_t count = std::size_t(pixels.width) * pixels.height * std::size_t(pixels.channels);
    if (pixels.bit_depth == 16) {
        const auto* in = reinterpret_cast<const std::uint16_t*>(pixels.buffer.data());
        for (std::size_t i = 0; i < count; ++i) out[i] = float(in[i]) / 65535.0f;
    } else {
        for (std::size_t i = 0; i < count; ++i) out[i] = float(pixels.buffer[i]) / 255.0f;
    }
    return image;
}

std::uint32_t quantize_value(float v, float max_value, Quantize q) {
    if (!(v >= 0.0f)) v = 0.0f;  // also maps NaN to 0
    v = std::min(v, 1.0f) * max_value;
    return std::uint32_t(q == Quantize::Round ? std::floor(v + 0.5f) : std::floor(v));
}

void write_png_file(const std::string& path, const Image& image, int bits, Quantize quantize,
                    const ImageMetadata& metadata) {
    FilePtr file = open_file(path, "wb");
    PngErrorContext context{path, {}};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, png_error_handler,
                                              png_warning_handler);
    png_infop info = png_create_info_struct(png);
    const int channels = image.channels();
    const int color_types[] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                               PNG_COLOR_TYPE_RGBA};
    const std::size_t row_values = std::size_t(image.width()) * std::size_t(channels);
    std::vector<unsigned char> row(row_values * std::size_t(bits / 8));
    // Objects with destructors are made before setjmp: png_longjmp (a write error such as a full
    // disk) returns there, and would skip the destructor of any object made after it.
    std::vector<png_text> texts;
    for (const auto& [key, value] : metadata) {
        png_text text{};
        text.compression = PNG_TEXT_COMPRESSION_NONE;
        text.key = const_cast<char*>(key.c_str());
        text.text = const_cast<char*>(value.c_str());
        text.text_length = value.size();
        texts.push_back(text);
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        throw_error("cannot write PNG '{}': {}", path, context.message);
    }
    png_init_io(png, file.get());
    png_set_IHDR(png, info, png_uint_32(image.width()), png_uint_32(image.height()), bits,
                 color_types[channels], PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    // Level 2 with the Sub and Up filters only: 3-5x faster to encode than libpng's default (level
    // 6, every filter tried per row) for 20-30 % larger files (docs/asset-formats.md, "PNG"). An
    // optimize run writes about 100 PNGs (maps, GLB, turntables), so this is seconds per asset.
    png_set_compression_level(png, 2);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB | PNG_FILTER_UP);
    if (!texts.empty()) png_set_text(png, info, texts.data(), int(texts.size()));
    png_write_info(png, info);
    const float max_value = bits == 16 ? 65535.0f : 255.0f;
    for (int y = 0; y < image.height(); ++y) {
        const float* in = image.pixel(0, y);
        for (std::size_t i = 0; i < row_values; ++i) {
            const std::uint32_t q = quantize_value(in[i], max_value, quantize);
            if (bits == 16) {
                row[2 * i] = static_cast<unsigned char>(q >> 8);  // PNG is big-endian
                row[2 * i + 1] = static_cast<unsigned char>(q & 0xff);
            } else {
                row[i] = static_cast<unsigned char>(q);
            }
        }
        png_write_row(png, row.data());
    }
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fflush(file.get()) != 0 || std::ferror(file.get()))
        throw_error("cannot write PNG '{}': {} (disk full?)", path, std::strerror(errno));
}

// ---- JPEG ------------------------------------------------------------------------------------

struct JpegError {
    jpeg_error_mgr base;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

void jpeg_error_exit(j_common_ptr cinfo) {
    auto* err = reinterpret_cast<JpegError*>(cinfo->err);
    (*cinfo->err->format_message)(cinfo, err->message);
    std::longjmp(err->jump, 1);
}

Image read_jpeg(std::FILE* file, const std::string& path, std::uint64_t file_size) {
    jpeg_decompress_struct cinfo;
    JpegError err;
    cinfo.err = jpeg_std_error(&err.base);
    err.base.error_exit = jpeg_error_exit;
    std::vector<unsigned char> buffer;
    if (setjmp(err.jump)) {
        jpeg_destroy_decompress(&cinfo);
        throw_error("cannot read JPEG '{}': {}", path, err.message);
    }
    jpeg_create_decompress(&cinfo);
    jpeg_stdio_src(&cinfo, file);
    jpeg_read_header(&cinfo, TRUE);
    if (cinfo.num_components != 1) cinfo.out_color_space = JCS_RGB;
    try {
        check_image_size(
            path,
            file_size,
            "JPEG",
            cinfo.image_width,
            cinfo.image_height,
            double(cinfo.image_width) * double(cinfo.image_height) * double(cinfo.num_components));
    } catch (...) {
        jpeg_destroy_decompress(&cinfo);
        throw;
    }
    jpeg_start_decompress(&cinfo);
    const int width = int(cinfo.output_width), height = int(cinfo.output_height);
    const int channels = int(cinfo.output_components);
    buffer.resize(std::size_t(width) * std::size_t(height) * std::size_t(channels));
    while (cinfo.output_scanline < cinfo.output_height) {
        JSAMPROW row = buffer.data() + std::size_t(cinfo.output_scanline) * std::size_t(width) * std::size_t(channels);
        jpeg_read_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    Image image(width, height, channels);
    for (std::size_t i = 0; i < buffer.size(); ++i) image.data()[i] = float(buffer[i]) / 255.0f;
    return image;
}

void write_jpeg_file(const std::string& path, const Image& image, int quality) {
    FilePtr file = open_file(path, "wb");
    jpeg_compress_struct cinfo;
    JpegError err;
    cinfo.err = jpeg_std_error(&err.base);
    err.base.error_exit = jpeg_error_exit;
    // No locals live across setjmp other than these (gcc's -Wclobbered).
    std::vector<unsigned char> row(std::size_t(image.width()) * 3);
    if (setjmp(err.jump)) {
        jpeg_destroy_compress(&cinfo);
        throw_error("cannot write JPEG '{}': {}", path, err.message);
    }
    jpeg_create_compress(&cinfo);
    jpeg_stdio_dest(&cinfo, file.get());
    cinfo.image_width = JDIMENSION(image.width());
    cinfo.image_height = JDIMENSION(image.height());
    cinfo.input_components = image.channels() >= 3 ? 3 : 1;
    cinfo.in_color_space = cinfo.input_components == 3 ? JCS_RGB : JCS_GRAYSCALE;
    jpeg_set_defaults(&cinfo);
    jpeg_set_quality(&cinfo, quality, TRUE);
    jpeg_start_compress(&cinfo, TRUE);
    while (cinfo.next_scanline < cinfo.image_height) {
        const int y = int(cinfo.next_scanline);
        for (int x = 0; x < image.width(); ++x)
            for (int c = 0; c < cinfo.input_components; ++c)
                row[std::size_t(x * cinfo.input_components + c)] =
                    static_cast<unsigned char>(quantize_value(image.at(x, y, c), 255.0f, Quantize::Round));
        JSAMPROW pointer = row.data();
        jpeg_write_scanlines(&cinfo, &pointer, 1);
    }
    jpeg_finish_compress(&cinfo);
    jpeg_destroy_compress(&cinfo);
    if (std::fflush(file.get()) != 0 || std::ferror(file.get()))
        throw_error("cannot write JPEG '{}': {} (disk full?)", path, std::strerror(errno));
}

// ---- EXR -------------------------------------------------------------------------------------

std::vector<std::string> default_channel_names(int channels) {
    switch (channels) {
        case 1: return {"Y"};
        case 2: return {"Y", "A"};
        case 3: return {"R", "G", "B"};
        case 4: return {"R", "G", "B", "A"};
        default: {
            std::vector<std::string> names;
            for (int c = 0; c < channels; ++c) names.push_back("C" + std::to_string(c));
            return names;
        }
    }
}

// Order channels of one layer the way a user expects (R,G,B,A / X,Y,Z / U,V,W), not alphabetically.
int channel_rank(const std::string& name) {
    static const char* order[] = {"R", "G", "B", "A", "X", "Y", "Z", "U", "V", "W"};
    for (int i = 0; i < 10; ++i)
        if (name == order[i]) return i;
    return 100;
}

}  // namespace

Image read_image(const std::string& path) {
    ImageMetadata unused;
    return read_image(path, unused);
}

Image read_image(const std::string& path, ImageMetadata& metadata) {
    metadata.clear();
    if (!std::filesystem::exists(path)) throw_error("cannot open '{}': no such file", path);
    unsigned char magic[4] = {0, 0, 0, 0};
    {
        FilePtr file = open_file(path, "rb");
        if (std::fread(magic, 1, 4, file.get()) != 4) throw_error("cannot read image '{}': file is too short", path);
    }
    if (magic[0] == 0x89 && magic[1] == 'P' && magic[2] == 'N' && magic[3] == 'G') {
        FilePtr file = open_file(path, "rb");
        return read_png(file.get(), path, file_size_or_zero(path), &metadata);
    }
    if (magic[0] == 0xFF && magic[1] == 0xD8) {
        FilePtr file = open_file(path, "rb");
        return read_jpeg(file.get(), path, file_size_or_zero(path));
    }
    if (magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) {
        std::vector<ExrLayer> layers = read_exr_layers(path, &metadata);
        int channels = 0;
        for (const auto& l : layers) channels += l.image.channels();
        Image out(layers[0].image.width(), layers[0].image.height(), channels);
        int offset = 0;
        for (const auto& layer : layers) {
            for (std::size_t p = 0; p < out.pixel_count(); ++p)
                for (int c = 0; c < layer.image.channels(); ++c)
                    out.data()[p * std::size_t(channels) + std::size_t(offset + c)] =
                        layer.image.data()[p * std::size_t(layer.image.channels()) + std::size_t(c)];
            offset += layer.image.channels();
        }
        return out;
    }
    throw_error("cannot read image '{}': not a PNG, JPEG or OpenEXR file", path);
}

Image decode_image(const std::string& bytes, const std::string& where) {
    const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
    const bool png = bytes.size() >= 4 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G';
    const bool jpeg = bytes.size() >= 2 && b[0] == 0xFF && b[1] == 0xD8;
    if (!png && !jpeg) throw_error("cannot read image '{}': not a PNG or JPEG", where);
    FilePtr file(fmemopen(const_cast<char*>(bytes.data()), bytes.size(), "rb"));
    if (!file) throw_error("cannot read image '{}': {}", where, std::strerror(errno));
    return png ? read_png(file.get(), where, bytes.size(), nullptr)
               : read_jpeg(file.get(), where, bytes.size());
}

void write_png(const std::string& path, const Image& image, int bits, Quantize quantize) {
    write_png(path, image, ImageMetadata{}, bits, quantize);
}

void check_output_extension(const std::string& path, const std::vector<std::string>& extensions,
                            const std::string& what) {
    const std::string ext = lower_extension(path);
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) return;
    std::string list;
    for (const auto& e : extensions) list += (list.empty() ? "" : ", ") + e;
    throw_error("{}: {} must be named {} (the extension chooses the format), got '{}'",
                path,
                what,
                list,
                ext.empty() ? "no extension" : ext);
}

void write_png(const std::string& path, const Image& image, const ImageMetadata& metadata, int bits,
               Quantize quantize) {
    check_output_extension(path, {".png"}, "a PNG file");
    for (const auto& entry : metadata)
        if (entry.first.empty() || entry.first.size() > 79)
            throw_error("cannot write PNG '{}': metadata key '{}' must have 1 to 79 characters", path, entry.first);
    if (bits != 8 && bits != 16) throw_error("cannot write PNG '{}': bit depth must be 8 or 16, got {}", path, bits);
    if (image.channels() < 1 || image.channels() > 4)
        throw_error("cannot write PNG '{}': {} channels (1 to 4 supported)", path, image.channels());
    if (image.empty()) throw_error("cannot write PNG '{}': the image is empty", path);
    write_atomically(path, [&](const std::string& tmp) { write_png_file(tmp, image, bits, quantize, metadata); });
}

void write_jpeg(const std::string& path, const Image& image, int quality) {
    check_output_extension(path, {".jpg", ".jpeg"}, "a JPEG file");
    if (quality < 1 || quality > 100)
        throw_error("cannot write JPEG '{}': quality must be in 1..100, got {}", path, quality);
    if (image.empty() || image.channels() < 1 || image.channels() > 4)
        throw_error("cannot write JPEG '{}': the image is empty or has {} channels (1 to 4 supported)",
                    path,
                    image.channels());
    write_atomically(path, [&](const std::string& tmp) { write_jpeg_file(tmp, image, quality); });
}

void write_image(const std::string& path, const Image& image, int png_bits, Quantize quantize) {
    check_output_extension(path, {".png", ".jpg", ".jpeg", ".exr"}, "an image");
    const std::string ext = lower_extension(path);
    if (ext == ".png")
        write_png(path, image, png_bits, quantize);
    else if (ext == ".exr")
        write_exr(path, image);
    else
        write_jpeg(path, image);
}

namespace {

// A layer to write, by reference: the images are not copied (a 4096^2 RGB float map is 201 MB,
// and an initializer list of ExrLayer copied it twice).
struct ExrLayerView {
    const std::string& name;
    const std::vector<std::string>& channel_names;
    const Image& image;
};

void write_exr_file(const std::string& path, const std::vector<ExrLayerView>& layers, ExrPixelType type,
                    const ImageMetadata& metadata) {
    check_output_extension(path, {".exr"}, "an OpenEXR file");
    if (layers.empty()) throw_error("cannot write EXR '{}': no layers", path);
    const int width = layers[0].image.width(), height = layers[0].image.height();
    if (width <= 0 || height <= 0) throw_error("cannot write EXR '{}': the image is empty", path);
    for (const auto& layer : layers) {
        if (layer.image.width() != width || layer.image.height() != height)
            throw_error("cannot write EXR '{}': layer '{}' is {}x{}, expected {}x{}", path, layer.name,
                        layer.image.width(), layer.image.height(), width, height);
        if (int(layer.channel_names.size()) != layer.image.channels())
            throw_error("cannot write EXR '{}': layer '{}' names {} channels but has {}", path, layer.name,
                        layer.channel_names.size(), layer.image.channels());
    }
    const Imf::PixelType pixel_type = type == ExrPixelType::Half ? Imf::HALF : Imf::FLOAT;
    write_atomically(path, [&](const std::string& tmp) {
        try {
            Imf::Header header(width, height);
            header.compression() = Imf::ZIP_COMPRESSION;
            for (const auto& [key, value] : metadata) header.insert(key, Imf::StringAttribute(value));
            Imf::FrameBuffer frame;
            // OpenEXR does not convert between the frame buffer's and the file's pixel types on
            // write, so half files are written from a half copy of the pixels.
            std::vector<std::vector<Imath::half>> half_copies;
            for (const auto& layer : layers) {
                const int channels = layer.image.channels();
                const std::size_t x_stride = std::size_t(channels), y_stride = x_stride * std::size_t(width);
                char* base = reinterpret_cast<char*>(const_cast<float*>(layer.image.data()));
                std::size_t element = sizeof(float);
                if (type == ExrPixelType::Half) {
                    half_copies.emplace_back(layer.image.values().begin(), layer.image.values().end());
                    base = reinterpret_cast<char*>(half_copies.back().data());
                    element = sizeof(Imath::half);
                }
                for (int c = 0; c < channels; ++c) {
                    const std::string name =
                        layer.name.empty() ? layer.channel_names[std::size_t(c)] : layer.name + "." + layer.channel_names[std::size_t(c)];
                    header.channels().insert(name, Imf::Channel(pixel_type));
                    frame.insert(name, Imf::Slice(pixel_type, base + element * std::size_t(c), element * x_stride,
                                                  element * y_stride));
                }
            }
            Imf::OutputFile file(tmp.c_str(), header, exr_threads());
            file.setFrameBuffer(frame);
            file.writePixels(height);
        } catch (const std::exception& e) {
            throw_error("cannot write EXR '{}': {}", path, e.what());
        }
    });
}

}  // namespace

void write_exr(const std::string& path, const std::vector<ExrLayer>& layers, ExrPixelType type) {
    std::vector<ExrLayerView> views;
    views.reserve(layers.size());
    for (const ExrLayer& layer : layers) views.push_back({layer.name, layer.channel_names, layer.image});
    write_exr_file(path, views, type, ImageMetadata{});
}

void write_exr(const std::string& path, const Image& image, ExrPixelType type) {
    write_exr(path, image, ImageMetadata{}, type);
}

void write_exr(const std::string& path, const Image& image, const ImageMetadata& metadata, ExrPixelType type) {
    const std::string no_name;
    const std::vector<std::string> channel_names = default_channel_names(image.channels());
    write_exr_file(path, {ExrLayerView{no_name, channel_names, image}}, type, metadata);
}

namespace {

// OpenEXR 3.1 allocates string, opaque and preview attributes at the size the file claims
// before reading them, so a 300-byte file can make it allocate gigabytes (found by fuzzing).
// The header is walked here first the way OpenEXR reads it -- fixed-size types consume their
// own size whatever the declared one, a channel list is parsed to its terminating empty name,
// everything else consumes the declared size -- and every claim is checked against the bytes
// left in the file. Layout: magic, version, then per header a list of name\0 type\0 int32 size
// + value ended by an empty name (multi-part files: a list of headers ended by an empty one).
struct NeedMoreHeader {};

// The sizes of the EXR attribute types whose values have a fixed size: OpenEXR reads that many
// bytes whatever size the file declares.
const std::map<std::string, std::size_t>& exr_fixed_attribute_sizes() {
    static const std::map<std::string, std::size_t> kFixed = {{"box2i", 16},
                                                              {"box2f", 16},
                                                              {"compression", 1},
                                                              {"lineOrder", 1},
                                                              {"float", 4},
                                                              {"double", 8},
                                                              {"int", 4},
                                                              {"v2i", 8},
                                                              {"v2f", 8},
                                                              {"v2d", 16},
                                                              {"v3i", 12},
                                                              {"v3f", 12},
                                                              {"v3d", 24},
                                                              {"m33f", 36},
                                                              {"m33d", 72},
                                                              {"m44f", 64},
                                                              {"m44d", 128},
                                                              {"tiledesc", 9},
                                                              {"chromaticities", 32},
                                                              {"envmap", 1},
                                                              {"keycode", 28},
                                                              {"timecode", 8},
                                                              {"rational", 8},
                                                              {"deepImageState", 1}};
    return kFixed;
}

// Walks the header in `bytes`, the first bytes of a file of `file_size` bytes; throws
// NeedMoreHeader when the header runs past `bytes` and the file is longer.
void walk_exr_header(const std::string& path, const std::string& bytes, std::uint64_t file_size) {
    std::size_t at = 8;
    if (bytes.size() < at) throw_error("cannot read EXR '{}': file is too short", path);
    const bool multipart = (std::uint8_t(bytes[5]) & 0x10) != 0;  // version field bit 12
    const auto truncated = [&]() {
        if (bytes.size() < file_size) throw NeedMoreHeader{};
        throw_error("cannot read EXR '{}': truncated or corrupt header", path);
    };
    const auto read_name = [&]() {
        const std::size_t end = bytes.find('\0', at);
        if (end == std::string::npos || end - at > 255) truncated();
        std::string name = bytes.substr(at, end - at);
        at = end + 1;
        return name;
    };
    const auto read_i32 = [&]() {
        if (bytes.size() - at < 4) truncated();
        std::int32_t v;
        std::memcpy(&v, bytes.data() + at, 4);
        at += 4;
        return std::int64_t(v);
    };
    const std::map<std::string, std::size_t>& kFixed = exr_fixed_attribute_sizes();
    // What OpenEXR allocates from once the header is read: the pixel window (line buffers) and
    // the chunk offset table (one 8-byte offset per line block or tile, all stored in the file).
    std::int64_t window[4] = {0, 0, -1, -1};
    std::int64_t tile_x = 0, tile_y = 0, channels = 0;
    bool have_window = false, tiled = false;
    const auto check_header = [&]() {
        if (!have_window) return;  // OpenEXR reports the missing attribute itself
        const std::int64_t width = window[2] - window[0] + 1, height = window[3] - window[1] + 1;
        if (width <= 0 || height <= 0) throw_error("cannot read EXR '{}': empty data window", path);
        check_image_size(path,
                         file_size,
                         "EXR",
                         std::uint64_t(width),
                         std::uint64_t(height),
                         2.0 * double(width) * double(height) * double(std::max<std::int64_t>(channels, 1)));
        if (tiled && (tile_x <= 0 || tile_y <= 0))
            throw_error("cannot read EXR '{}': tile size {}x{}", path, tile_x, tile_y);
        const double chunks =
            tiled ? std::ceil(double(width) / double(tile_x)) * std::ceil(double(height) / double(tile_y))
                  : std::ceil(double(height) / 256.0);  // at most 256 lines per block (DWAB)
        if (chunks * 8.0 > double(file_size))
            throw_error("cannot read EXR '{}': its {} chunk offsets cannot fit in a file of {} bytes",
                        path,
                        std::uint64_t(chunks),
                        file_size);
        have_window = tiled = false;
        channels = 0;
    };
    for (int header = 0; header < 1024; ++header) {
        for (int attribute = 0;; ++attribute) {
            const std::string name = read_name();
            if (name.empty()) {
                if (attribute == 0) return;  // end of a multi-part header list
                check_header();
                if (!multipart) return;
                break;
            }
            if (attribute >= 65536) truncated();
            const std::string type = read_name();
            const std::int64_t size = read_i32();
            const std::uint64_t left = file_size - std::min<std::uint64_t>(file_size, at);
            if (size < 0 || std::uint64_t(size) > left)
                throw_error(
                    "cannot read EXR '{}': header attribute '{}' claims {} bytes, more than the file holds",
                    path,
                    name,
                    size);
            const auto fixed = kFixed.find(type);
            if (fixed != kFixed.end()) {
                if (bytes.size() - at < fixed->second) truncated();
                if (name == "dataWindow" && type == "box2i") {
                    for (std::int64_t& v : window) v = read_i32();
                    have_window = true;
                    at -= 16;
                } else if (name == "tiles" && type == "tiledesc") {
                    tile_x = std::uint32_t(read_i32());
                    tile_y = std::uint32_t(read_i32());
                    tiled = true;
                    at -= 8;
                }
                at += fixed->second;
            } else if (type == "chlist") {
                while (!read_name().empty()) {  // name, then pixel type, linear + 3 reserved, x/y sampling
                    if (bytes.size() - at < 16) truncated();
                    at += 16;
                    ++channels;
                }
            } else if (type == "preview") {
                const std::int64_t width = std::uint32_t(read_i32()), height = std::uint32_t(read_i32());
                if (double(width) * double(height) * 4.0 >
                    double(file_size - std::min<std::uint64_t>(file_size, at)))
                    throw_error("cannot read EXR '{}': preview image of {}x{} pixels is larger than the file",
                                path,
                                width,
                                height);
                at += std::size_t(width * height * 4);
            } else {
                at += std::size_t(size);  // string, stringvector, opaque and other sized types
            }
            if (at > bytes.size()) truncated();
        }
    }
}

void check_exr_header(const std::string& path) {
    const std::uint64_t size = file_size_or_zero(path);
    FilePtr file = open_file(path, "rb");
    std::string bytes;
    for (std::size_t want = 1 << 16;; want *= 4) {  // most headers are a few hundred bytes
        const std::size_t have = bytes.size();
        const std::size_t target = std::size_t(std::min<std::uint64_t>(size, want));
        bytes.resize(std::max(target, have));
        bytes.resize(have + std::fread(bytes.data() + have, 1, bytes.size() - have, file.get()));
        const bool complete = bytes.size() < target || bytes.size() >= size;
        try {
            walk_exr_header(path, bytes, complete ? bytes.size() : size);
            return;
        } catch (const NeedMoreHeader&) {
            // only thrown while the file has more bytes than were read
        }
    }
}

}  // namespace

std::vector<ExrLayer> read_exr_layers(const std::string& path, ImageMetadata* metadata) {
    if (!std::filesystem::exists(path)) throw_error("cannot open '{}': no such file", path);
    check_exr_header(path);
    try {
        // OpenEXR itself refuses larger data windows while reading the header, before it
        // allocates its line-offset table.
        static const bool limited = [] {
            Imf::Header::setMaxImageSize(kMaxImageSide, kMaxImageSide);
            Imf::Header::setMaxTileSize(kMaxImageSide, kMaxImageSide);
            return true;
        }();
        (void)limited;
        Imf::InputFile file(path.c_str(), exr_threads());
        const Imath::Box2i window = file.header().dataWindow();
        if (metadata)
            for (auto it = file.header().begin(); it != file.header().end(); ++it)
                if (const auto* text = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
                    (*metadata)[it.name()] = text->value();
        const std::int64_t wide_width = std::int64_t(window.max.x) - window.min.x + 1;
        const std::int64_t wide_height = std::int64_t(window.max.y) - window.min.y + 1;
        if (wide_width <= 0 || wide_height <= 0) throw_error("cannot read EXR '{}': empty data window", path);
        std::size_t channel_count = 0;
        for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                throw_error(
                    "cannot read EXR '{}': subsampled channel '{}' is not supported", path, it.name());
            ++channel_count;
        }
        if (channel_count == 0) throw_error("cannot read EXR '{}': the file has no channels", path);
        check_image_size(path,
                         file_size_or_zero(path),
                         "EXR",
                         std::uint64_t(wide_width),
                         std::uint64_t(wide_height),
                         2.0 * double(wide_width) * double(wide_height) * double(channel_count));
        const int width = int(wide_width), height = int(wide_height);
        std::map<std::string, std::vector<std::string>> layer_channels;  // layer -> channel suffixes
        std::vector<std::string> layer_order;
        for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
            const std::string full = it.name();
            const auto dot = full.rfind('.');
            const std::string layer = dot == std::string::npos ? "" : full.substr(0, dot);
            const std::string channel = dot == std::string::npos ? full : full.substr(dot + 1);
            if (!layer_channels.count(layer)) layer_order.push_back(layer);
            layer_channels[layer].push_back(channel);
        }
        std::vector<ExrLayer> layers;
        Imf::FrameBuffer frame;
        layers.reserve(layer_order.size());
        for (const auto& name : layer_order) {
            auto channels = layer_channels[name];
            std::stable_sort(channels.begin(), channels.end(),
                             [](const std::string& a, const std::string& b) { return channel_rank(a) < channel_rank(b); });
            layers.push_back(ExrLayer{name, channels, Image(width, height, int(channels.size()))});
        }
        for (auto& layer : layers) {
            const int n = layer.image.channels();
            for (int c = 0; c < n; ++c) {
                const std::string full = layer.name.empty() ? layer.channel_names[std::size_t(c)]
                                                            : layer.name + "." + layer.channel_names[std::size_t(c)];
                // OpenEXR addresses pixel (x, y) of the data window as base + x * xStride +
                // y * yStride, so base lies before the image by the window's origin. That origin
                // can be far outside the image (any int in a file), where pointer arithmetic would
                // overflow (undefined behaviour, found by the image fuzzer): the address is
                // computed in unsigned integers, which wrap, and OpenEXR's own sum lands back
                // inside the image.
                const std::uintptr_t origin =
                    (std::uintptr_t(std::intptr_t(window.min.x)) +
                     std::uintptr_t(std::intptr_t(window.min.y)) * std::uintptr_t(width)) *
                    std::uintptr_t(sizeof(float) * std::size_t(n));
                char* base = reinterpret_cast<char*>(reinterpret_cast<std::uintptr_t>(layer.image.data() + c) - origin);
                frame.insert(full, Imf::Slice(Imf::FLOAT, base, sizeof(float) * std::size_t(n),
                                              sizeof(float) * std::size_t(n) * std::size_t(width)));
            }
        }
        file.setFrameBuffer(frame);
        file.readPixels(window.min.y, window.max.y);
        return layers;
    } catch (const tdf::Error&) {
        throw;
    } catch (const std::exception& e) {
        throw_error("cannot read EXR '{}': {}", path, e.what());
    }
}

}  // namespace tdf
