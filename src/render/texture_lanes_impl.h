// The kernel of texture_lanes.h, written once over an instruction set's operations `V` and
// included by texture_lanes_avx512.cpp and texture_lanes_avx2.cpp inside an anonymous namespace
// (no symbol of it is shared between the two). Scalar reference: sample_pair<3> and level_pair in
// texture.cpp, wrapped_footprint and blend_footprint<3> in core/image_ops.h.

// The lanes' blend of one level: the footprint at `uv` on level `level`, both maps' texels
// weighted as blend_footprint<3> weighs them. Returns false (nothing written) when a lane of
// `lanes` would need wrapping beyond one texel or has a non-finite coordinate.
template <class V>
inline bool blend_level_lanes(const PairLevel& level, typename V::F u, typename V::F v, typename V::M lanes,
                              typename V::F* a, typename V::F* b) {
    using F = typename V::F;
    using I = typename V::I;
    const F w = V::set(float(level.width)), h = V::set(float(level.height));
    const F half = V::set(0.5f), one = V::set(1.f);
    const F x = V::sub(V::mul(u, w), half), y = V::sub(V::mul(V::sub(one, v), h), half);
    const F fx = V::floor(x), fy = V::floor(y);
    // floor in [-1, size - 1]: one wrap at most (NaN fails the comparison too).
    const F minus_one = V::set(-1.f);
    const auto inside = V::mask_and(V::mask_and(V::ge(fx, minus_one), V::le(fx, V::sub(w, one))),
                                    V::mask_and(V::ge(fy, minus_one), V::le(fy, V::sub(h, one))));
    if (!V::covers(inside, lanes)) return false;
    const F ax = V::sub(x, fx), ay = V::sub(y, fy);
    const I wi = V::seti(level.width), hi = V::seti(level.height), zero = V::seti(0), one_i = V::seti(1);
    I x0 = V::cvtt(fx), y0 = V::cvtt(fy);
    x0 = V::selecti(V::lti(x0, zero), V::subi(wi, one_i), x0);
    y0 = V::selecti(V::lti(y0, zero), V::subi(hi, one_i), y0);
    I x1 = V::addi(x0, one_i), y1 = V::addi(y0, one_i);
    x1 = V::selecti(V::eqi(x1, wi), zero, x1);
    y1 = V::selecti(V::eqi(y1, hi), zero, y1);
    const I three = V::seti(3);
    const I row0 = V::muli(y0, wi), row1 = V::muli(y1, wi);
    const I i00 = V::muli(V::addi(row0, x0), three), i10 = V::muli(V::addi(row0, x1), three);
    const I i01 = V::muli(V::addi(row1, x0), three), i11 = V::muli(V::addi(row1, x1), three);
    const F cx = V::sub(one, ax), cy = V::sub(one, ay);
    const F w00 = V::mul(cx, cy), w10 = V::mul(ax, cy), w01 = V::mul(cx, ay), w11 = V::mul(ax, ay);
    for (int k = 0; k < 3; ++k) {
        const I dk = V::seti(k);
        const I j00 = V::addi(i00, dk), j10 = V::addi(i10, dk), j01 = V::addi(i01, dk),
                j11 = V::addi(i11, dk);
        const auto blend = [&](const float* texels) {
            F s = V::mul(w00, V::gather(lanes, texels, j00));
            s = V::add(s, V::mul(w10, V::gather(lanes, texels, j10)));
            s = V::add(s, V::mul(w01, V::gather(lanes, texels, j01)));
            return V::add(s, V::mul(w11, V::gather(lanes, texels, j11)));
        };
        a[k] = blend(level.a);
        b[k] = blend(level.b);
    }
    return true;
}

template <class V>
void sample_pairs(PairLookups& q) {
    using F = typename V::F;
    using I = typename V::I;
    constexpr int N = V::kLanes;
    alignas(64) float covered[N], lod[N], u[N], v[N];
    alignas(64) int l0s[N];
    const F top = V::set(float(q.top));
    for (std::size_t i0 = 0; i0 < q.n; i0 += N) {
        const int count = q.n - i0 < std::size_t(N) ? int(q.n - i0) : N;
        const float *in_covered = q.covered + i0, *in_lod = q.lod + i0, *in_u = q.u + i0, *in_v = q.v + i0;
        if (count < N) {  // the last group: copied, zeros beyond the end
            for (int j = 0; j < N; ++j) {
                const bool in = j < count;
                covered[j] = in ? in_covered[j] : 0.f, lod[j] = in ? in_lod[j] : 0.f;
                u[j] = in ? in_u[j] : 0.f, v[j] = in ? in_v[j] : 0.f;
            }
            in_covered = covered, in_lod = lod, in_u = u, in_v = v;
        }
        const auto active = V::gt(V::loadu(in_covered), V::set(0.f));
        if (!V::any(active)) continue;
        // level_pair: !(lod > 0) -> 0 (NaN too), at most top, then its integer part and fraction.
        F l = V::loadu(in_lod);
        l = V::select(V::gt(l, V::set(0.f)), l, V::set(0.f));
        l = V::min(l, top);
        const I l0 = V::cvtt(l);
        const F frac = V::sub(l, V::cvt(l0));
        V::storei(l0s, l0);
        const auto blends_next = V::mask_and(V::gt(frac, V::set(0.f)), V::lti(l0, V::seti(q.top)));
        const F fu = V::loadu(in_u), fv = V::loadu(in_v);
        // The lanes one level at a time (a group that crosses a LOD contour reads two levels).
        auto todo = active;
        auto left = V::none();
        while (V::any(todo)) {
            const int level = l0s[V::first(todo)];
            const auto lanes = V::mask_and(todo, V::eqi(l0, V::seti(level)));
            todo = V::mask_andnot(lanes, todo);
            const auto next = V::mask_and(lanes, blends_next);
            F a[3], b[3];
            bool done = blend_level_lanes<V>(q.levels[level], fu, fv, lanes, a, b);
            if (done && V::any(next)) {
                F na[3], nb[3];
                done = blend_level_lanes<V>(q.levels[level + 1], fu, fv, next, na, nb);
                for (int k = 0; done && k < 3; ++k) {
                    a[k] = V::select(next, V::add(a[k], V::mul(frac, V::sub(na[k], a[k]))), a[k]);
                    b[k] = V::select(next, V::add(b[k], V::mul(frac, V::sub(nb[k], b[k]))), b[k]);
                }
            }
            if (!done) {
                left = V::mask_or(left, lanes);
                continue;
            }
            for (int k = 0; k < 3; ++k) {
                V::store_lanes(q.out_a + std::size_t(k) * q.plane + i0, lanes, a[k]);
                V::store_lanes(q.out_b + std::size_t(k) * q.plane + i0, lanes, b[k]);
            }
        }
        const unsigned left_bits = V::bits(left);
        for (int j = 0; j < count; ++j)
            if (left_bits >> j & 1u) q.left[q.left_count++] = std::uint32_t(i0 + std::size_t(j));
    }
}
