#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/tactile/height_input.h>
#include <tdf/tactile/npy_reader.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "common/test_paths.h"
#include "unit/tactile_test_util.h"

using namespace tdf;
using tdf::test::error_of;

namespace {

// A .npy image: version 1.0 header padded to 64 bytes, then raw data.
std::string npy_bytes(const std::string& descr, const std::string& shape, const std::string& data,
                      bool fortran = false) {
    std::string header = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
                         ", 'shape': " + shape + ", }";
    while ((10 + header.size() + 1) % 64 != 0) header += ' ';
    header += '\n';
    std::string out = "\x93NUMPY";
    out += char(1);
    out += char(0);
    out += char(header.size() & 0xff);
    out += char(header.size() >> 8);
    return out + header + data;
}

template <typename T>
std::string raw(const std::vector<T>& values) {
    return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

void put16(std::string& s, std::uint32_t v) {
    s += char(v & 0xff);
    s += char((v >> 8) & 0xff);
}
void put32(std::string& s, std::uint32_t v) {
    put16(s, v & 0xffff);
    put16(s, v >> 16);
}

std::string deflate_raw(const std::string& data) {
    z_stream z{};
    EXPECT_EQ(deflateInit2(&z, 6, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::string out(deflateBound(&z, uLong(data.size())), '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

// A minimal zip archive (what np.savez / np.savez_compressed write) of named members.
std::string zip_bytes(const std::vector<std::pair<std::string, std::string>>& members, bool compress) {
    std::string zip, directory;
    for (const auto& [name, content] : members) {
        const std::string stored = compress ? deflate_raw(content) : content;
        const auto crc =
            std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(content.data()), uInt(content.size())));
        const std::uint32_t offset = std::uint32_t(zip.size());
        auto common = [&](std::string& s) {
            put16(s, 20), put16(s, 0), put16(s, compress ? 8 : 0), put16(s, 0), put16(s, 0x21);
            put32(s, crc), put32(s, std::uint32_t(stored.size())), put32(s, std::uint32_t(content.size()));
            put16(s, std::uint16_t(name.size())), put16(s, 0);
        };
        put32(zip, 0x04034b50u);
        common(zip);
        zip += name + stored;
        put32(directory, 0x02014b50u);
        put16(directory, 20);
        common(directory);
        put16(directory, 0), put16(directory, 0), put16(directory, 0), put32(directory, 0),
            put32(directory, offset);
        directory += name;
    }
    const std::uint32_t start = std::uint32_t(zip.size());
    zip += directory;
    put32(zip, 0x06054b50u);
    put16(zip, 0), put16(zip, 0), put16(zip, std::uint16_t(members.size())),
        put16(zip, std::uint16_t(members.size()));
    put32(zip, std::uint32_t(directory.size())), put32(zip, start), put16(zip, 0);
    return zip;
}

std::string write_file(const std::string& name, const std::string& bytes) {
    const std::string path = test::scratch_dir() + "/" + name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

const std::string kStrawberry = "tactile/gelsight_raw/strawberry_00000_gxgy.npz";

}  // namespace

TEST(NpyReader, ReadsDtypesAndFortranOrder) {
    const NpyArray f8 = parse_npy(npy_bytes("<f8", "(2, 3)", raw<double>({1, 2, 3, 4, 5, 6.5})), "f8");
    EXPECT_EQ(f8.shape, (std::vector<std::size_t>{2, 3}));
    EXPECT_EQ(f8.at(1, 2), 6.5);
    // Fortran order: memory holds columns; values come back row-major.
    const NpyArray f4 = parse_npy(npy_bytes("<f4", "(2, 3)", raw<float>({1, 4, 2, 5, 3, 6}), true), "f4");
    EXPECT_EQ(f4.values, (std::vector<double>{1, 2, 3, 4, 5, 6}));
    const NpyArray u1 =
        parse_npy(npy_bytes("|u1", "(1, 2, 3)", raw<std::uint8_t>({0, 1, 2, 253, 254, 255})), "u1");
    EXPECT_EQ(u1.at(0, 1, 2), 255.0);
    const NpyArray i2 = parse_npy(npy_bytes(">i2", "(2,)", std::string("\xff\xfe\x01\x00", 4)), "i2");
    EXPECT_EQ(i2.values, (std::vector<double>{-2, 256}));
    const NpyArray f2 =
        parse_npy(npy_bytes("<f2", "(3,)", raw<std::uint16_t>({0x3c00, 0xc000, 0x0001})), "f2");
    EXPECT_EQ(f2.values[0], 1.0);
    EXPECT_EQ(f2.values[1], -2.0);
    EXPECT_NEAR(f2.values[2], 5.96e-8, 1e-10);  // smallest subnormal half
    const NpyArray scalar = parse_npy(npy_bytes("<f4", "()", raw<float>({4.5f})), "0-d");
    EXPECT_TRUE(scalar.shape.empty());
    EXPECT_EQ(scalar.values, (std::vector<double>{4.5}));
}

TEST(NpyReader, StoredAndDeflatedNpzGiveTheSameArrays) {
    const std::vector<std::pair<std::string, std::string>> members = {
        {"dm.npy", npy_bytes("<f8", "(3, 4)", raw<double>({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}))},
        {"image.npy", npy_bytes("|u1", "(3, 4, 3)", std::string(36, '\x07'))}};
    const auto stored = read_npz(write_file("stored.npz", zip_bytes(members, false)));
    const auto deflated = read_npz(write_file("deflated.npz", zip_bytes(members, true)));
    ASSERT_EQ(stored.size(), 2u);
    ASSERT_TRUE(stored.count("dm") && deflated.count("dm") && deflated.count("image"));
    EXPECT_EQ(stored.at("dm").values, deflated.at("dm").values);
    EXPECT_EQ(deflated.at("dm").at(2, 3), 11.0);
    EXPECT_EQ(deflated.at("image").shape, (std::vector<std::size_t>{3, 4, 3}));
}

TEST(NpyReader, BadInputsNameTheFile) {
    const std::string dm = npy_bytes("<f8", "(4, 4)", raw<double>(std::vector<double>(16, 1.0)));
    const std::string good = zip_bytes({{"dm.npy", dm}}, false);
    const std::string truncated = write_file("truncated.npz", good.substr(0, good.size() / 2));
    EXPECT_NE(error_of([&] { read_npz(truncated); }).find(truncated), std::string::npos);

    const std::string text = write_file(
        "text.npz", zip_bytes({{"dm.npy", npy_bytes("<U4", "(2,)", std::string(32, 'a'))}}, false));
    const std::string message = error_of([&] { load_height_input(text); });
    EXPECT_NE(message.find(text), std::string::npos) << message;
    EXPECT_NE(message.find("dtype"), std::string::npos) << message;

    const std::string ints = write_file(
        "ints.npz", zip_bytes({{"dm.npy", npy_bytes("<i4", "(4, 4)", std::string(64, '\0'))}}, false));
    EXPECT_NE(error_of([&] { load_height_input(ints); }).find("expected a float array"), std::string::npos);

    const std::string missing = write_file("missing.npz", zip_bytes({{"image.npy", dm}}, false));
    const std::string missing_message = error_of([&] { load_height_input(missing); });
    EXPECT_NE(missing_message.find("no 'gx' array"), std::string::npos) << missing_message;

    std::vector<double> values(16, 1.0);
    values[5] = std::numeric_limits<double>::quiet_NaN();
    const std::string nan =
        write_file("nan.npz", zip_bytes({{"dm.npy", npy_bytes("<f8", "(4, 4)", raw(values))}}, false));
    const std::string nan_message = error_of([&] { load_height_input(nan); });
    EXPECT_NE(nan_message.find(nan), std::string::npos);
    EXPECT_NE(nan_message.find("row 1, column 1"), std::string::npos) << nan_message;

    EXPECT_NE(error_of([&] { parse_npy("not an array", "x.npy"); }).find("x.npy"), std::string::npos);
    EXPECT_NE(error_of([&] {
                  parse_npy(npy_bytes("<f8", "(4, 4)", std::string(8, '\0')), "short.npy");
              }).find("truncated"),
              std::string::npos);
}

TEST(NpyReader, ReadsTheStrawberryCapture) {
    TDF_REQUIRE_SHARED_DATA(kStrawberry);
    const auto arrays = read_npz(test::shared_data_dir() + "/" + kStrawberry);
    for (const char* name : {"dm", "gx", "gy", "dm_zero", "nz_mask", "image"})
        ASSERT_TRUE(arrays.count(name)) << name;
    const NpyArray& dm = arrays.at("dm");
    EXPECT_EQ(dm.dtype, "<f8");
    EXPECT_EQ(dm.shape, (std::vector<std::size_t>{240, 320}));
    const auto [lo, hi] = std::minmax_element(dm.values.begin(), dm.values.end());
    EXPECT_NEAR(*lo, -0.78, 0.01);  // data README: range -0.78..5.65 mm
    EXPECT_NEAR(*hi, 5.65, 0.01);
    EXPECT_EQ(arrays.at("image").dtype, "|u1");
    EXPECT_EQ(arrays.at("image").shape, (std::vector<std::size_t>{240, 320, 3}));
}

TEST(NpyReader, ValueBeyondFloatRangeIsAnErrorNamingTheFile) {
    // 1e300 is a finite float64 but +Inf as a 32-bit height (then NaN normals): refused.
    std::vector<double> values(16, 0.5);
    values[6] = 1e300;
    const std::string path = write_file("huge_value.npy", npy_bytes("<f8", "(4, 4)", raw(values)));
    const std::string message = error_of([&] { load_height_input(path); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find("row 1, column 2"), std::string::npos) << message;
    EXPECT_NE(message.find("32-bit float"), std::string::npos) << message;
    values[6] = 3e38;  // still a float
    EXPECT_NO_THROW(
        load_height_input(write_file("large_value.npy", npy_bytes("<f8", "(4, 4)", raw(values)))));
}

TEST(NpyReader, NpzMemberWithBadCrcIsRefused) {
    const std::string dm = npy_bytes("<f8", "(4, 4)", raw<double>(std::vector<double>(16, 1.0)));
    for (const bool compress : {false, true}) {
        std::string zip = zip_bytes({{"dm.npy", dm}}, compress);
        EXPECT_NO_THROW(read_npz(write_file("crc_ok.npz", zip)));
        // Flip one data byte of the member (inside the stored/deflated payload): the CRC no
        // longer matches (for a deflated member the stream may also fail to inflate).
        const std::size_t payload = 30 + 6 + (compress ? 20 : 100);
        zip[payload] = char(zip[payload] ^ 0x01);
        const std::string path = write_file(compress ? "crc_bad_deflated.npz" : "crc_bad.npz", zip);
        const std::string message = error_of([&] { read_npz(path); });
        EXPECT_NE(message.find(path + ": dm.npy"), std::string::npos) << message;
        if (!compress) {
            EXPECT_NE(message.find("CRC mismatch"), std::string::npos) << message;
        }
    }
}

TEST(NpyReader, HugeClaimedSizesAreRefusedBeforeAllocating) {
    // Shape entries within bounds whose product overflows 64 bits.
    const std::string overflow =
        npy_bytes("<f8", "(1099511627776, 1099511627776, 1099511627776)", std::string(64, '\0'));
    EXPECT_NE(error_of([&] { parse_npy(overflow, "overflow.npy"); }).find("overflow.npy"), std::string::npos);
    // A deflated member claiming 4 GB uncompressed from a few bytes.
    std::string zip = zip_bytes({{"dm.npy", std::string(64, 'a')}}, true);
    const std::size_t directory = zip.rfind(std::string("PK\x01\x02", 4));
    ASSERT_NE(directory, std::string::npos);
    for (int k = 0; k < 4; ++k) zip[directory + 24 + std::size_t(k)] = char(0xfe);
    const std::string path = write_file("bomb.npz", zip);
    const std::string message = error_of([&] { read_npz(path); });
    EXPECT_NE(message.find("impossible"), std::string::npos) << message;
    EXPECT_NE(message.find(path), std::string::npos) << message;
}
