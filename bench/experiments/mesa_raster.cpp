// Experiment behind the choice of the raster producer (README "tdf render", "Raster producer"):
// the same visibility as tdf's own rasterizer (raster.h) drawn by Mesa's OpenGL through EGL
// surfaceless (llvmpipe on a machine without a GPU), on the bench scene of render_bench.cpp.
// Prints the time per frame of both and how many pixels agree (triangle id; barycentrics).
//
// Not part of the build or of CI (it needs libEGL/libOpenGL from Debian's Mesa packages):
//   cmake -S . -B build -DTDF_MESA_EXPERIMENT=ON && cmake --build build --target tdf_mesa_raster_experiment
//   LP_NUM_THREADS=1 ./build/bench/tdf_mesa_raster_experiment 1    (threads for llvmpipe and tdf)
#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <tdf/core/parallel.h>
#include <tdf/render/raster.h>
#include <tdf/scene/procedural_mesh.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <utility>
#include <vector>

using namespace tdf;

namespace {

constexpr int kSize = 512;

void fail(const char* what) {
    std::fprintf(stderr, "mesa_raster: %s failed\n", what);
    std::exit(1);
}

GLuint compile(GLenum type, const char* source) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        std::fprintf(stderr, "%s\n", log);
        fail("shader compile");
    }
    return s;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
    // Optional thread count for tdf (llvmpipe takes LP_NUM_THREADS).
    const ThreadLimit limit(argc > 1 ? std::atoi(argv[1]) : 0);
    // EGL surfaceless context (EGL_MESA_platform_surfaceless), desktop GL 3.3 core.
    auto get_platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!get_platform_display) fail("eglGetPlatformDisplayEXT");
    EGLDisplay display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY || !eglInitialize(display, nullptr, nullptr)) fail("eglInitialize");
    // No config needed for a context that only draws into framebuffer objects
    // (EGL_KHR_no_config_context).
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI");
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                         3,
                                         EGL_CONTEXT_MINOR_VERSION,
                                         3,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                         EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                         EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
    if (context == EGL_NO_CONTEXT || !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context))
        fail("eglCreateContext");
    std::printf("GL renderer: %s\n", reinterpret_cast<const char*>(glGetString(GL_RENDERER)));

    // The bench scene: 100k-triangle sphere, 512x512, same camera.
    const TriangleMesh mesh = make_uv_sphere(1.f, 320, 160);
    const Camera camera = Camera::orbit(-15, 30, 2.5f, 49.1f, kSize, kSize);
    const std::vector<Vec4f> clip = clip_positions(mesh, camera);

    // Unindexed corners with barycentric attributes (1,0), (0,1), (0,0) as nvdiffrast's GL path.
    std::vector<float> corners;
    corners.reserve(mesh.triangles.size() * 18);
    for (const Vec3i& t : mesh.triangles) {
        const int idx[3] = {t.x, t.y, t.z};
        const float bary[3][2] = {{1, 0}, {0, 1}, {0, 0}};
        for (int k = 0; k < 3; ++k) {
            const Vec4f& c = clip[std::size_t(idx[k])];
            corners.insert(corners.end(), {c.x, c.y, c.z, c.w, bary[k][0], bary[k][1]});
        }
    }
    GLuint vao = 0, vbo = 0;
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(corners.size() * sizeof(float)), corners.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glVertexAttribPointer(
        1, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(4 * sizeof(float)));
    glEnableVertexAttribArray(0);
    glEnableVertexAttribArray(1);

    const GLuint program = glCreateProgram();
    glAttachShader(program, compile(GL_VERTEX_SHADER, R"(#version 330 core
layout(location = 0) in vec4 clip;
layout(location = 1) in vec2 bary;
out vec2 v_bary;
void main() { gl_Position = clip; v_bary = bary; })"));
    glAttachShader(program, compile(GL_FRAGMENT_SHADER, R"(#version 330 core
in vec2 v_bary;
out vec4 out_rast;
void main() { out_rast = vec4(v_bary, gl_FragCoord.z * 2.0 - 1.0, float(gl_PrimitiveID + 1)); })"));
    glLinkProgram(program);
    glUseProgram(program);

    GLuint fbo = 0, color = 0, depth = 0;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenRenderbuffers(1, &color);
    glBindRenderbuffer(GL_RENDERBUFFER, color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, kSize, kSize);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, kSize, kSize);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail("framebuffer");
    glViewport(0, 0, kSize, kSize);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);

    std::vector<float> gl_rast(std::size_t(kSize) * kSize * 4);
    auto draw = [&] {
        glClearColor(0, 0, 0, 0);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glDrawArrays(GL_TRIANGLES, 0, GLsizei(mesh.triangles.size() * 3));
        // Row 0 of the read-back is window y = 0 = NDC y -1: nvdiffrast's row order.
        glReadPixels(0, 0, kSize, kSize, GL_RGBA, GL_FLOAT, gl_rast.data());
    };
    draw();  // warm-up (shader compilation)
    // Wall time per frame (median) and process CPU time per frame (all threads, mean): the CPU
    // time is the steadier figure on a shared machine.
    constexpr int kFrames = 10;
    std::vector<double> gl_times, own_times;
    std::clock_t c0 = std::clock();
    for (int k = 0; k < kFrames; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        draw();
        gl_times.push_back(seconds_since(t0));
    }
    const double gl_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC / kFrames;
    RasterBuffer own;
    c0 = std::clock();
    for (int k = 0; k < kFrames; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        rasterize(clip, mesh.triangles, kSize, kSize, own);
        own_times.push_back(seconds_since(t0));
    }
    const double own_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC / kFrames;
    std::sort(gl_times.begin(), gl_times.end());
    std::sort(own_times.begin(), own_times.end());

    std::size_t covered_gl = 0, covered_own = 0, same_id = 0, both = 0;
    double max_bary = 0;
    std::vector<double> bary_diffs;
    // Pixels where the two pick different triangles, and how many of them have the other's
    // triangle as a 4-neighbour in tdf's image (i.e. lie on a shared edge).
    std::size_t differ = 0, differ_on_edge = 0;
    for (std::size_t i = 0; i < own.rast.size(); ++i) {
        const int id_gl = int(gl_rast[4 * i + 3]) - 1, id_own = own.triangle(i);
        covered_gl += id_gl >= 0;
        covered_own += id_own >= 0;
        if (id_gl < 0 || id_own < 0) continue;
        ++both;
        if (id_gl != id_own) {
            ++differ;
            const int x = int(i % kSize), y = int(i / kSize);
            bool edge = false;
            for (const auto [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                const int xx = x + dx, yy = y + dy;
                if (xx >= 0 && yy >= 0 && xx < kSize && yy < kSize && own.triangle(own.index(xx, yy)) == id_gl)
                    edge = true;
            }
            differ_on_edge += edge;
            continue;
        }
        ++same_id;
        bary_diffs.push_back(std::max(std::fabs(gl_rast[4 * i] - own.rast[i].x),
                                      std::fabs(gl_rast[4 * i + 1] - own.rast[i].y)));
        max_bary = std::max({max_bary,
                             double(std::fabs(gl_rast[4 * i] - own.rast[i].x)),
                             double(std::fabs(gl_rast[4 * i + 1] - own.rast[i].y))});
    }
    std::printf("Mesa (EGL surfaceless): %.2f ms wall (median), %.2f ms CPU per frame (draw + read-back)\n",
                1e3 * gl_times[kFrames / 2],
                1e3 * gl_cpu);
    std::printf("tdf rasterize: %.2f ms wall (median), %.2f ms CPU per frame on %d threads\n",
                1e3 * own_times[kFrames / 2],
                1e3 * own_cpu,
                ThreadLimit::current());
    std::printf(
        "covered pixels: Mesa %zu, tdf %zu; same triangle on %zu of %zu pixels covered by both (%.4f%%); "
        "max |barycentric difference| there %.3g\n",
        covered_gl,
        covered_own,
        same_id,
        both,
        100.0 * double(same_id) / double(std::max<std::size_t>(1, both)),
        max_bary);
    std::sort(bary_diffs.begin(), bary_diffs.end());
    if (!bary_diffs.empty())
        std::printf("barycentric difference: median %.3g, 99th percentile %.3g; %zu pixels differ in triangle, %zu "
                    "of them next to a pixel of the other triangle\n",
                    bary_diffs[bary_diffs.size() / 2], bary_diffs[bary_diffs.size() * 99 / 100], differ,
                    differ_on_edge);
    eglTerminate(display);
    return 0;
}
