// Direction interpolation on the GPU: the exact Delaunay barycentric weights of
// DirectionInterpolator::weights (core/DirectionInterpolation.h), per fragment. The table
// (DirectionTable there, made by materials/DirectionLookup) splits the disc map into a grid of
// cells, each listing the triangles that overlap it and, where the cell reaches outside the
// triangulation, the hull edges that can be the nearest; this function tests only its cell's
// candidates with the CPU's formulas, in the CPU's operation order, so both agree to float
// rounding. DirectionInterpolator::lookupTable is this function on the CPU.

// materials/ShaderInterface.h kDirectionGrid / kDirectionTableWidth (checked by a test).
const int btfDirectionGrid = 32;
const int btfDirectionTableWidth = 1024;
// Below this barycentric weight a point is outside the triangulation (kOutsideHull in
// core/DirectionInterpolation.cpp).
const float btfOutsideHull = 1e-5;

vec2 btfDirectionToDisc(vec3 d) {
    d.z = max(d.z, 0.0);
    d = normalize(d);
    return d.xy / (1.0 + d.z);
}

vec4 btfDirectionTexel(sampler2D table, int address) {
    return texelFetch(table, ivec2(address & (btfDirectionTableWidth - 1),
                                   address / btfDirectionTableWidth), 0);
}

float btfCross(vec2 u, vec2 v) {
    return u.x * v.y - u.y * v.x;
}

/** Up to 3 measured direction indices and weights (>= 0, sum 1) for direction d. */
void btfLookupDirections(sampler2D table, vec3 d, out ivec3 index, out vec3 weight) {
    vec2 p = btfDirectionToDisc(d);
    ivec2 cell = clamp(ivec2(floor((p + 1.0) * (0.5 * float(btfDirectionGrid)))), ivec2(0),
                       ivec2(btfDirectionGrid - 1));
    vec4 range = btfDirectionTexel(table, cell.y * btfDirectionGrid + cell.x);
    float bestLowest = -3.0e38;
    vec3 best = vec3(0.0);
    int bestIndices = 0;
    int trianglesEnd = int(range.x) + 3 * int(range.y);
    for (int r = int(range.x); r < trianglesEnd; r += 3) {
        vec4 ab = btfDirectionTexel(table, r);
        vec4 c = btfDirectionTexel(table, r + 1);
        float w0 = btfCross(c.xy - ab.zw, p - ab.zw) * c.z;
        float w1 = btfCross(ab.xy - c.xy, p - c.xy) * c.z;
        vec3 w = vec3(w0, w1, 1.0 - w0 - w1);
        float lowest = min(min(w.x, w.y), w.z);
        if (lowest > bestLowest) {
            bestLowest = lowest;
            best = w;
            bestIndices = r + 2;
        }
        if (lowest >= 0.0) break;
    }
    if (bestLowest < -btfOutsideHull && range.w > 0.0) {
        // Outside the triangulation: the closest point of its boundary.
        float bestDistance = 3.0e38;
        int edgesEnd = int(range.z) + 2 * int(range.w);
        for (int r = int(range.z); r < edgesEnd; r += 2) {
            vec4 ab = btfDirectionTexel(table, r);
            vec2 e = ab.zw - ab.xy;
            // A segment of length 0 (a set of one direction) is its point.
            float length2 = dot(e, e);
            float t = length2 > 0.0 ? clamp(dot(p - ab.xy, e) / length2, 0.0, 1.0) : 0.0;
            vec2 q = ab.xy + t * e - p;
            float distance = dot(q, q);
            if (distance < bestDistance) {
                bestDistance = distance;
                best = vec3(1.0 - t, t, 0.0);
                bestIndices = r + 1;
            }
        }
    } else {
        best = max(best, vec3(0.0));
        best /= best.x + best.y + best.z;
    }
    index = ivec3(btfDirectionTexel(table, bestIndices).xyz + 0.5);
    weight = best;
}
