#include <tdf/scene/embree_scene.h>

#include <tdf/core/error.h>

#include <cstring>
#include <mutex>

namespace tdf {

// Embree reports errors through a C callback. Throwing through Embree's C API is not safe, so
// the callback only records the first message; throw_if_error() turns it into a tdf::Error.
struct EmbreeScene::ErrorSink {
    std::mutex mutex;
    std::string message;

    static void callback(void* user, RTCError code, const char* text) {
        auto* sink = static_cast<ErrorSink*>(user);
        std::lock_guard<std::mutex> lock(sink->mutex);
        if (sink->message.empty())
            sink->message = fmt::format("Embree error {}: {}", int(code), text ? text : "(no message)");
    }
};

EmbreeScene::EmbreeScene(const TriangleMesh& mesh, PacketWidth width)
    : m_errors(std::make_unique<ErrorSink>()) {
    if (mesh.triangles.empty() || mesh.positions.empty())
        throw_error("{}: cannot build a ray-tracing scene from an empty mesh",
                    mesh.source_path.empty() ? "mesh" : mesh.source_path);
    m_device = rtcNewDevice(nullptr);
    if (!m_device) throw_error("cannot create an Embree device (error {})", int(rtcGetDeviceError(nullptr)));
    rtcSetDeviceErrorFunction(m_device, &ErrorSink::callback, m_errors.get());
    try {
        build(mesh, width);
    } catch (...) {
        // The destructor does not run for a throwing constructor.
        if (m_scene) rtcReleaseScene(m_scene);
        rtcReleaseDevice(m_device);
        throw;
    }
}

void EmbreeScene::build(const TriangleMesh& mesh, PacketWidth width) {
#if defined(__x86_64__) || defined(__i386__)
    m_packet16 = width == PacketWidth::Native && __builtin_cpu_supports("avx512f") != 0;
#endif

    m_scene = rtcNewScene(m_device);
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geometry = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
    if (!vertices || !indices) {
        rtcReleaseGeometry(geometry);
        throw_if_error("allocating geometry buffers");
        throw_error("Embree could not allocate buffers for {} triangles", mesh.triangles.size());
    }
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) std::memcpy(vertices + 3 * i, &mesh.positions[i], 12);
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) indices[3 * i + k] = unsigned(mesh.triangles[i][k]);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(m_scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(m_scene);
    m_triangle_count = mesh.triangles.size();
    throw_if_error("building the scene");
}

EmbreeScene::~EmbreeScene() {
    if (m_scene) rtcReleaseScene(m_scene);
    if (m_device) rtcReleaseDevice(m_device);
}

void EmbreeScene::throw_if_error(const char* during) const {
    std::string message;
    {
        std::lock_guard<std::mutex> lock(m_errors->mutex);
        message = m_errors->message;
    }
    if (!message.empty()) throw_error("{} while {}", message, during);
}

}  // namespace tdf
