#pragma once
/// NumPy `.npy` arrays and `.npz` archives (a zip of `.npy` members), read without Python.
///
/// Supported: format versions 1.0-3.0, C or Fortran order, little-endian or single-byte dtypes
/// `f2 f4 f8 i1 i2 i4 i8 u1 u2 u4 u8 b1` (big-endian `>` dtypes are byte-swapped). Zip members
/// may be STORED (what `np.savez` writes) or DEFLATE-compressed (`np.savez_compressed`); ZIP64
/// sizes are honoured; every member's CRC-32 is checked. Values are converted to double on load
/// (every supported dtype fits).
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace tdf {

/// One array. `values` are in C (row-major) order whatever the file's order was.
struct NpyArray {
    std::string dtype;               ///< numpy descr as written, e.g. "<f8", "|u1"
    std::vector<std::size_t> shape;  ///< empty for a 0-d array
    std::vector<double> values;      ///< product(shape) values, row-major

    std::size_t size() const { return values.size(); }
    /// Value at (row, col) of a 2-D array, or (row, col, channel) of a 3-D one.
    double at(std::size_t row, std::size_t col, std::size_t channel = 0) const;
};

/// Parses one `.npy` image held in memory. `where` names it in errors ("file.npz: dm.npy").
NpyArray parse_npy(const std::string& bytes, const std::string& where);

/// Reads a `.npy` file. Throws tdf::Error naming the file when it is missing, truncated or
/// of an unsupported dtype.
NpyArray read_npy(const std::string& path);

/// Reads every member of a `.npz` archive, keyed by name without the `.npy` suffix
/// ("dm", "gx", ...). Throws tdf::Error naming the file (and member) on any problem.
std::map<std::string, NpyArray> read_npz(const std::string& path);

}  // namespace tdf
