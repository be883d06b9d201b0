#pragma once
/// An Embree 3 device + scene holding one triangle mesh, built once and traced many times.
/// Geometry 0 is the mesh; Embree's primID is the index into TriangleMesh::triangles.
/// No back-face culling (spec 2.2: both sides are visible).
#include <tdf/mesh/triangle_mesh.h>

#include <embree3/rtcore.h>

#include <memory>
#include <string>

namespace tdf {

/// The width of the ray packets traced: the CPU's native one (16 with AVX-512, else 8), or 8 on
/// any CPU, so that an AVX-512 machine also runs and tests the 8-wide path AVX2 machines take.
enum class PacketWidth { Native, Eight };

class EmbreeScene {
public:
    /// Builds the BVH (medium quality). Throws tdf::Error when Embree reports an error, e.g.
    /// when the device cannot be created or memory runs out.
    explicit EmbreeScene(const TriangleMesh& mesh, PacketWidth width = PacketWidth::Native);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    RTCScene handle() const { return m_scene; }
    RTCDevice device() const { return m_device; }
    std::size_t triangle_count() const { return m_triangle_count; }
    /// True when 16-wide packets run natively (the CPU has AVX-512); otherwise tracing uses
    /// 8-wide packets (16-wide ones would be emulated, toolchain notes 3).
    bool native_packet16() const { return m_packet16; }

    /// Throws tdf::Error with the message of the last Embree error on this device, if any.
    void throw_if_error(const char* during) const;

private:
    void build(const TriangleMesh& mesh, PacketWidth width);

    struct ErrorSink;
    std::unique_ptr<ErrorSink> m_errors;
    RTCDevice m_device = nullptr;
    RTCScene m_scene = nullptr;
    std::size_t m_triangle_count = 0;
    bool m_packet16 = false;
};

}  // namespace tdf
