// The light tree of --light-selection tree (LIGHT_TREE; src/render/light_tree.rs builds it
// and describes the buffer): next-event estimation picks an emissive triangle by a
// stochastic descent from the root, each child chosen in proportion to its importance at
// the shading point x with normal n (Conty Estevez & Kulla 2018, "Importance Sampling of
// Many Lights with Adaptive Tree Splitting", as pbrt-v4's BVHLightSampler and
// LightBounds::Importance), and `tree_prob` gives that probability for a given light by
// walking from its leaf up to the root through the parents, with the same arithmetic per
// node. The normal bound is two-sided (|cos|), so transmitting surfaces lose nothing.
// Requires TEXEL_READS, `params`, types.glsl (NO_LIGHT); included by lights.glsl.
#ifndef LIGHT_TREE_GLSL
#define LIGHT_TREE_GLSL

#define NO_NODE 0xffffffffu

#if TEXEL_READS
uniform utextureBuffer light_tree;
uvec4 tree_at(uint i) { return texelFetch(light_tree, int(i)); }
#else
layout(std430) readonly buffer light_tree { uvec4 tree_data[]; };
uvec4 tree_at(uint i) { return tree_data[i]; }
#endif

struct TreeNode {
    vec3 bmin;
    float power;
    vec3 bmax;
    float cos_o;  // the normals' cone: half-angle's cosine around `axis`
    vec3 axis;
    float cos_e;  // the emission's spread beyond the normals (0: cosine emitters)
    uvec4 links;  // child 0, child 1 (NO_NODE: a leaf), parent (root: NO_NODE), light
};

TreeNode tree_node(uint i) {
    uint e = 1u + 4u * i;
    uvec4 a = tree_at(e), b = tree_at(e + 1u), c = tree_at(e + 2u);
    TreeNode n;
    n.bmin = uintBitsToFloat(a.xyz);
    n.power = uintBitsToFloat(a.w);
    n.bmax = uintBitsToFloat(b.xyz);
    n.cos_o = uintBitsToFloat(b.w);
    n.axis = uintBitsToFloat(c.xyz);
    n.cos_e = uintBitsToFloat(c.w);
    n.links = tree_at(e + 3u);
    return n;
}

// The probability of going into the tree (the area lights' share of the power).
float tree_share() { return uintBitsToFloat(tree_at(0u).z); }

// Light i's entry: (leaf, alias and threshold among the other lights, pick probability
// of a light outside the tree).
uvec4 tree_light(uint i) { return tree_at(tree_at(0u).y + i); }

// cos(max(0, a - b)) and sin(max(0, a - b)) from the sines and cosines of a and b.
float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    return cos_a > cos_b ? 1.0 : cos_a * cos_b + sin_a * sin_b;
}
float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
    return cos_a > cos_b ? 0.0 : sin_a * cos_b - cos_a * sin_b;
}

// A conservative estimate of node `nd`'s contribution at x with normal n (n = 0: none):
// power over the squared distance to the box's centre (at least half its diagonal), times
// the cosine at the lights bounded from above over the box and the normals' cone, times
// the cosine at x bounded likewise (pbrt-v4's LightBounds::Importance). Zero only where
// no light of the node can shine on x.
float tree_importance(TreeNode nd, vec3 x, vec3 n) {
    vec3 pc = 0.5 * (nd.bmin + nd.bmax);
    vec3 d = x - pc;
    float dist2 = dot(d, d);
    vec3 wi = dist2 > 0.0 ? d * inversesqrt(dist2) : nd.axis;
    // The directions from x to the box lie within angle theta_b of -wi (its bounding sphere).
    vec3 r = nd.bmax - pc;
    float r2 = dot(r, r);
    float cos_b = -1.0, sin_b = 0.0;
    if (dist2 > r2) {
        float sin2 = r2 / dist2;
        cos_b = sqrt(max(0.0, 1.0 - sin2));
        sin_b = sqrt(sin2);
    }
    float cos_w = dot(nd.axis, wi);
    float sin_w = sqrt(max(0.0, 1.0 - cos_w * cos_w));
    float sin_o = sqrt(max(0.0, 1.0 - nd.cos_o * nd.cos_o));
    // The smallest angle between a light's normal and the direction to x.
    float cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, nd.cos_o);
    float sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, nd.cos_o);
    float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    if (cos_p <= nd.cos_e) return 0.0;
    float imp = nd.power * cos_p / max(dist2, 0.5 * length(nd.bmax - nd.bmin));
    if (n != vec3(0.0)) {
        float cos_i = abs(dot(wi, n));
        float sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
        imp *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    return max(imp, 0.0);
}

// The probability of taking child 0 of inner node `nd` at (x, n); negative when neither
// child can shine on x.
float tree_child0_prob(TreeNode nd, vec3 x, vec3 n) {
    float i0 = tree_importance(tree_node(nd.links.x), x, n);
    float i1 = tree_importance(tree_node(nd.links.y), x, n);
    return i0 + i1 > 0.0 ? i0 / (i0 + i1) : -1.0;
}

// The descent: a light of the tree drawn with probability `prob` (without the tree's
// share) from u in [0, 1), remapped at each node; NO_LIGHT (prob 0) when no light of the
// tree can shine on x.
uint tree_pick(float u, vec3 x, vec3 n, out float prob) {
    prob = 1.0;
    TreeNode nd = tree_node(0u);
    while (nd.links.x != NO_NODE) {
        float p0 = tree_child0_prob(nd, x, n);
        if (p0 < 0.0) {
            prob = 0.0;
            return NO_LIGHT;
        }
        bool first = u < p0;
        u = min(first ? u / p0 : (u - p0) / (1.0 - p0), ONE_MINUS_EPSILON);
        prob *= first ? p0 : 1.0 - p0;
        nd = tree_node(first ? nd.links.x : nd.links.y);
    }
    return nd.links.w;
}

// The probability that tree_pick draws light `index` at (x, n) (0 for lights outside
// the tree): from its leaf up, the same factor per node as the descent's.
float tree_prob(uint index, vec3 x, vec3 n) {
    uint node = tree_light(index).x;
    if (node == NO_NODE) return 0.0;
    float prob = 1.0;
    uint parent = tree_at(4u + 4u * node).z;
    while (parent != NO_NODE) {
        TreeNode nd = tree_node(parent);
        float p0 = tree_child0_prob(nd, x, n);
        if (p0 < 0.0) return 0.0;
        prob *= nd.links.x == node ? p0 : 1.0 - p0;
        node = parent;
        parent = nd.links.z;
    }
    return prob;
}

// Next-event estimation's pick: into the tree with probability tree_share(), else one of
// the other lights from their alias table (as pick_light_at's), with its power
// probability. `prob` is the probability of the light returned (NO_LIGHT: 0).
uint tree_nee_pick(float u, vec3 x, vec3 n, out float prob) {
    float share = tree_share();
    if (u < share) {
        uint li = tree_pick(min(u / share, ONE_MINUS_EPSILON), x, n, prob);
        prob *= share;
        return li;
    }
    uint count = params.dims.z;
    float y = min((u - share) / (1.0 - share), ONE_MINUS_EPSILON) * float(count);
    uint i = min(uint(y), count - 1u);
    uvec4 e = tree_light(i);
    uint li = y - float(i) < uintBitsToFloat(e.z) ? i : e.y;
    prob = uintBitsToFloat(tree_light(li).w);
    return li;
}

// The probability that tree_nee_pick picks light `index` at (x, n).
float tree_nee_prob(uint index, vec3 x, vec3 n) {
    uvec4 e = tree_light(index);
    if (e.x == NO_NODE) return uintBitsToFloat(e.w);
    return tree_share() * tree_prob(index, x, n);
}

#endif
