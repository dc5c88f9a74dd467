#!/usr/bin/env python3
# Small skinned and morphed glTF files for issue 17 (test_skin.c embeds their output; e2e_gltf.sh
# runs this): usage skin_gltf.py skin|morph [c]  (c: as a C string literal).
#   skin: two joints (root translated 0 -> 0.5 in x over t 0..1, tip rotated 0 -> 90 deg about z),
#         a lower quad bound to root, an upper quad (z = 0.01) bound to tip with its bottom
#         vertices blended 0.5/0.5; the skinned node carries a translation glTF says to ignore.
#   morph: one triangle, one target (v2 += (0,0,1), its normal += (1,0,0)); node 0 animates the
#         weight 0 -> 1 over t 0..1, node 1 has node.weights 0.75, node 2 the mesh default 0.25.
import struct, base64, json, math, sys
def pack(fmt, vals): return struct.pack('<'+fmt*len(vals) if len(fmt)==1 else fmt, *vals)
class B:
    def __init__(s): s.data=b''; s.views=[]; s.acc=[]
    def add(s, raw, ctype, typ, count, **kw):
        while len(s.data)%4: s.data+=b'\0'
        s.views.append({"buffer":0,"byteOffset":len(s.data),"byteLength":len(raw)})
        s.data+=raw
        a={"bufferView":len(s.views)-1,"componentType":ctype,"count":count,"type":typ}; a.update(kw)
        s.acc.append(a); return len(s.acc)-1
    def f(s, vals, typ, n): return s.add(struct.pack('<%df'%len(vals),*vals),5126,typ,len(vals)//n)
def skin():
    b=B()
    z=0.01
    P=[-0.5,0,0, 0.5,0,0, 0.5,1,0, -0.5,1,0,  -0.5,1,z, 0.5,1,z, 0.5,2,z, -0.5,2,z]
    N=[0,0,1]*8
    J=[0,0,0,0]*4+[0,1,0,0]*2+[1,0,0,0]*2
    W=[1,0,0,0]*4+[0.5,0.5,0,0]*2+[1,0,0,0]*2
    I=[0,1,2,0,2,3, 4,5,6,4,6,7]
    pa=b.f(P,"VEC3",3); na=b.f(N,"VEC3",3)
    ja=b.add(struct.pack('<32B',*J),5121,"VEC4",8)
    wa=b.f(W,"VEC4",4)
    ia=b.add(struct.pack('<12H',*I),5123,"SCALAR",12)
    ibm=[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1,  1,0,0,0, 0,1,0,0, 0,0,1,0, 0,-1,0,1]
    iba=b.add(struct.pack('<32f',*ibm),5126,"MAT4",2)
    ta=b.f([0,1],"SCALAR",1); b.acc[ta].update({"min":[0],"max":[1]})
    tr=b.f([0,0,0, 0.5,0,0],"VEC3",3)
    s=math.sqrt(0.5)
    ro=b.f([0,0,0,1, 0,0,s,s],"VEC4",4)
    g={"asset":{"version":"2.0"},"scenes":[{"nodes":[0,1]}],
       "nodes":[{"name":"body","mesh":0,"skin":0,"translation":[5,5,5]},{"name":"root","children":[2]},{"name":"tip","translation":[0,1,0]}],
       "skins":[{"joints":[1,2],"inverseBindMatrices":iba}],
       "meshes":[{"primitives":[{"attributes":{"POSITION":pa,"NORMAL":na,"JOINTS_0":ja,"WEIGHTS_0":wa},"indices":ia,"material":0}]}],
       "materials":[{"doubleSided":True,"pbrMetallicRoughness":{"metallicFactor":0}}],
       "animations":[{"channels":[{"sampler":0,"target":{"node":1,"path":"translation"}},{"sampler":1,"target":{"node":2,"path":"rotation"}}],
                      "samplers":[{"input":ta,"output":tr},{"input":ta,"output":ro}]}],
       "accessors":b.acc,"bufferViews":b.views,
       "buffers":[{"byteLength":len(b.data),"uri":"data:application/octet-stream;base64,"+base64.b64encode(b.data).decode()}]}
    return g
def morph():
    b=B()
    pa=b.f([0,0,0, 1,0,0, 0,1,0],"VEC3",3); na=b.f([0,0,1]*3,"VEC3",3)
    dp=b.f([0,0,0, 0,0,0, 0,0,1],"VEC3",3); dn=b.f([0,0,0, 0,0,0, 1,0,0],"VEC3",3)
    ta=b.f([0,1],"SCALAR",1); b.acc[ta].update({"min":[0],"max":[1]})
    wo=b.f([0,1],"SCALAR",1)
    g={"asset":{"version":"2.0"},"scenes":[{"nodes":[0,1,2]}],
       "nodes":[{"name":"animated","mesh":0},{"name":"fixed","mesh":0,"weights":[0.75],"translation":[2,0,0]},{"name":"default","mesh":0,"translation":[4,0,0]}],
       "meshes":[{"weights":[0.25],"primitives":[{"attributes":{"POSITION":pa,"NORMAL":na},"targets":[{"POSITION":dp,"NORMAL":dn}]}]}],
       "animations":[{"channels":[{"sampler":0,"target":{"node":0,"path":"weights"}}],"samplers":[{"input":ta,"output":wo}]}],
       "accessors":b.acc,"bufferViews":b.views,
       "buffers":[{"byteLength":len(b.data),"uri":"data:application/octet-stream;base64,"+base64.b64encode(b.data).decode()}]}
    return g
which=sys.argv[1]
g=skin() if which=="skin" else morph()
s=json.dumps(g,separators=(',',':'))
if len(sys.argv)>2 and sys.argv[2]=="c":
    print('"'+s.replace('\\','\\\\').replace('"','\\"')+'"')
else:
    print(s)
