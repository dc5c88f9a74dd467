/* tool_draco_box.cpp — test helper (issue 17, KHR_draco_mesh_compression): writes a unit box
 * (24 vertices with per-face normals, 12 triangles) into DIR, uncompressed and through the
 * Draco encoder library, plus hostile variants, for test_draco.c and e2e_draco.sh:
 *   plain-box.gltf + plain-box.bin   accessors with buffer views (the reference)
 *   draco-box.gltf + draco-box.bin   the same box, Draco-compressed (edgebreaker, positions
 *                                    14 bits, normals 10 bits)
 *   draco-box.glb                    the same as one GLB (JSON chunk + BIN chunk)
 *   draco-corrupt.gltf + .bin        the Draco bytes with the body overwritten
 *   draco-badid.gltf                 NORMAL mapped to a Draco attribute id that does not exist
 *   draco-count.gltf                 the POSITION accessor's count one short
 *   draco-noview.gltf                the extension's bufferView does not exist
 * usage: ispm_test_draco_box DIR */
#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct box {
    float pos[24][3], nrm[24][3];
    unsigned short idx[36];
};

box make_box()
{
    box b;
    int v = 0, t = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            const int u = (axis + 1) % 3, w = (axis + 2) % 3;
            const float cu[4] = {-0.5f, 0.5f, 0.5f, -0.5f}, cw[4] = {-0.5f, -0.5f, 0.5f, 0.5f};
            for (int k = 0; k < 4; k++) {
                b.pos[v + k][axis] = 0.5f * static_cast<float>(sign);
                b.pos[v + k][u] = cu[k];
                b.pos[v + k][w] = sign > 0 ? cw[k] : -cw[k];
                b.nrm[v + k][0] = b.nrm[v + k][1] = b.nrm[v + k][2] = 0.0f;
                b.nrm[v + k][axis] = static_cast<float>(sign);
            }
            /* (u, w, axis) is right-handed, so 0-1-2 turns counter-clockwise seen from +axis;
             * the -axis face mirrors w, which keeps it counter-clockwise seen from outside. */
            const int tri[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k++)
                b.idx[t++] = static_cast<unsigned short>(v + tri[k]);
            v += 4;
        }
    return b;
}

bool write_file(const std::string &path, const void *data, size_t size)
{
    FILE *f = std::fopen(path.c_str(), "wb");
    if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) {
        std::fprintf(stderr, "ispm_test_draco_box: cannot write %s\n", path.c_str());
        return false;
    }
    return true;
}

bool write_text(const std::string &path, const std::string &text) { return write_file(path, text.data(), text.size()); }

const char HEAD[] = "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
                    "\"nodes\":[{\"mesh\":0}],\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorFactor\":"
                    "[0.8,0.6,0.4,1],\"metallicFactor\":0}}],";
const char ACCESSORS[] = "{\"componentType\":5123,\"count\":36,\"type\":\"SCALAR\"%s},"
                         "{\"componentType\":5126,\"count\":%d,\"type\":\"VEC3\",\"min\":[-0.5,-0.5,-0.5],"
                         "\"max\":[0.5,0.5,0.5]%s},"
                         "{\"componentType\":5126,\"count\":24,\"type\":\"VEC3\"%s}";

std::string draco_gltf(const char *uri, size_t draco_len, int pos_id, int nrm_id, int pos_count)
{
    char acc[600], buf[1400];
    std::snprintf(acc, sizeof acc, ACCESSORS, "", pos_count, "", "");
    std::snprintf(buf, sizeof buf,
                  "%s\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],"
                  "\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],"
                  "\"meshes\":[{\"name\":\"box\",\"primitives\":[{\"attributes\":{\"POSITION\":1,\"NORMAL\":2},"
                  "\"indices\":0,\"material\":0,\"extensions\":{\"KHR_draco_mesh_compression\":{\"bufferView\":0,"
                  "\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d}}}}]}],\"accessors\":[%s],"
                  "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu}],\"buffers\":[{\"byteLength\":%zu%s%s%s}]}",
                  HEAD, pos_id, nrm_id, acc, draco_len, draco_len, uri ? ",\"uri\":\"" : "", uri ? uri : "",
                  uri ? "\"" : "");
    return buf;
}

void put32(std::vector<unsigned char> &out, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        out.push_back(static_cast<unsigned char>(v >> (8 * k)));
}

} // namespace

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: ispm_test_draco_box DIR\n");
        return 2;
    }
    const std::string dir = std::string(argv[1]) + "/";
    const box b = make_box();

    /* The reference: positions, normals, indices in one buffer. */
    std::vector<unsigned char> plain(sizeof b.pos + sizeof b.nrm + sizeof b.idx);
    std::memcpy(plain.data(), b.pos, sizeof b.pos);
    std::memcpy(plain.data() + sizeof b.pos, b.nrm, sizeof b.nrm);
    std::memcpy(plain.data() + sizeof b.pos + sizeof b.nrm, b.idx, sizeof b.idx);
    char acc[600], text[1400];
    std::snprintf(acc, sizeof acc, ACCESSORS, ",\"bufferView\":2", 24, ",\"bufferView\":0", ",\"bufferView\":1");
    std::snprintf(text, sizeof text,
                  "%s\"meshes\":[{\"name\":\"box\",\"primitives\":[{\"attributes\":{\"POSITION\":1,\"NORMAL\":2},"
                  "\"indices\":0,\"material\":0}]}],\"accessors\":[%s],\"bufferViews\":[{\"buffer\":0,"
                  "\"byteLength\":288},{\"buffer\":0,\"byteOffset\":288,\"byteLength\":288},{\"buffer\":0,"
                  "\"byteOffset\":576,\"byteLength\":72}],\"buffers\":[{\"byteLength\":648,\"uri\":\"plain-box.bin\"}]}",
                  HEAD, acc);
    if (!write_file(dir + "plain-box.bin", plain.data(), plain.size()) || !write_text(dir + "plain-box.gltf", text))
        return 1;

    /* The same triangles through Draco. */
    draco::TriangleSoupMeshBuilder builder;
    builder.Start(12);
    const int pa = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    const int na = builder.AddAttribute(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32);
    for (int f = 0; f < 12; f++) {
        const unsigned short *t = b.idx + 3 * f;
        builder.SetAttributeValuesForFace(pa, draco::FaceIndex(f), b.pos[t[0]], b.pos[t[1]], b.pos[t[2]]);
        builder.SetAttributeValuesForFace(na, draco::FaceIndex(f), b.nrm[t[0]], b.nrm[t[1]], b.nrm[t[2]]);
    }
    std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
    if (!mesh) {
        std::fprintf(stderr, "ispm_test_draco_box: the mesh builder failed\n");
        return 1;
    }
    draco::Encoder enc;
    enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
    enc.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, 10);
    enc.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer out;
    const draco::Status st = enc.EncodeMeshToBuffer(*mesh, &out);
    if (!st.ok()) {
        std::fprintf(stderr, "ispm_test_draco_box: encoding failed: %s\n", st.error_msg());
        return 1;
    }
    if (mesh->num_points() != 24) {
        std::fprintf(stderr, "ispm_test_draco_box: %u points after the builder, want 24\n", mesh->num_points());
        return 1;
    }
    const int pid = static_cast<int>(mesh->attribute(pa)->unique_id());
    const int nid = static_cast<int>(mesh->attribute(na)->unique_id());
    const std::vector<unsigned char> drc(out.data(), out.data() + out.size());
    std::vector<unsigned char> corrupt = drc;
    for (size_t i = corrupt.size() / 3; i < corrupt.size(); i++)
        corrupt[i] = static_cast<unsigned char>(0xA5 ^ i);

    /* GLB: a 12-byte header, the JSON chunk (space-padded), the BIN chunk (zero-padded). */
    std::string json = draco_gltf(nullptr, drc.size(), pid, nid, 24);
    while (json.size() % 4)
        json += ' ';
    std::vector<unsigned char> bin = drc;
    while (bin.size() % 4)
        bin.push_back(0);
    std::vector<unsigned char> glb = {'g', 'l', 'T', 'F'};
    put32(glb, 2);
    put32(glb, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
    put32(glb, static_cast<uint32_t>(json.size()));
    put32(glb, 0x4E4F534Au);
    glb.insert(glb.end(), json.begin(), json.end());
    put32(glb, static_cast<uint32_t>(bin.size()));
    put32(glb, 0x004E4942u);
    glb.insert(glb.end(), bin.begin(), bin.end());

    const int bad_id = 1 + (pid > nid ? pid : nid);
    std::string noview = draco_gltf("draco-box.bin", drc.size(), pid, nid, 24);
    const std::string view0 = "{\"bufferView\":0,\"attributes\"";
    noview.replace(noview.find(view0), view0.size(), "{\"bufferView\":5,\"attributes\"");
    bool ok = write_file(dir + "draco-box.bin", drc.data(), drc.size()) &&
              write_text(dir + "draco-box.gltf", draco_gltf("draco-box.bin", drc.size(), pid, nid, 24)) &&
              write_file(dir + "draco-box.glb", glb.data(), glb.size()) &&
              write_file(dir + "draco-corrupt.bin", corrupt.data(), corrupt.size()) &&
              write_text(dir + "draco-corrupt.gltf", draco_gltf("draco-corrupt.bin", drc.size(), pid, nid, 24)) &&
              write_text(dir + "draco-badid.gltf", draco_gltf("draco-box.bin", drc.size(), pid, bad_id, 24)) &&
              write_text(dir + "draco-count.gltf", draco_gltf("draco-box.bin", drc.size(), pid, nid, 23)) &&
              write_text(dir + "draco-noview.gltf", noview);
    if (ok)
        std::printf("draco box: %zu bytes (uncompressed %zu), POSITION id %d, NORMAL id %d\n", drc.size(),
                    plain.size(), pid, nid);
    return ok ? 0 : 1;
}
