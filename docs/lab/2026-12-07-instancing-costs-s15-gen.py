import json, math, random, struct, zlib, sys
def png(path, w, h, f):
    raw = b''.join(b'\x00' + bytes(int(255*max(0,min(1,f(x/w,y/h)))) for x in range(w)) for y in range(h))
    def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t+d) & 0xffffffff)
    open(path,'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0)) + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
def icosphere(level):
    t=(1+5**.5)/2
    v=[(-1,t,0),(1,t,0),(-1,-t,0),(1,-t,0),(0,-1,t),(0,1,t),(0,-1,-t),(0,1,-t),(t,0,-1),(t,0,1),(-t,0,-1),(-t,0,1)]
    v=[tuple(c/math.sqrt(sum(x*x for x in p)) for c in p) for p in v]
    f=[(0,11,5),(0,5,1),(0,1,7),(0,7,10),(0,10,11),(1,5,9),(5,11,4),(11,10,2),(10,7,6),(7,1,8),(3,9,4),(3,4,2),(3,2,6),(3,6,8),(3,8,9),(4,9,5),(2,4,11),(6,2,10),(8,6,7),(9,8,1)]
    for _ in range(level):
        cache={}; nf=[]
        def mid(a,b):
            k=(min(a,b),max(a,b))
            if k not in cache:
                p=[(v[a][i]+v[b][i])/2 for i in range(3)]; n=math.sqrt(sum(x*x for x in p)); v.append(tuple(x/n for x in p)); cache[k]=len(v)-1
            return cache[k]
        for a,b,c in f:
            ab,bc,ca=mid(a,b),mid(b,c),mid(c,a); nf+= [(a,ab,ca),(b,bc,ab),(c,ca,bc),(ab,bc,ca)]
        f=nf
    return v,f
def ply(path, level):
    v,f=icosphere(level)
    uv=[(0.5+math.atan2(p[2],p[0])/(2*math.pi), 0.5-math.asin(max(-1,min(1,p[1])))/math.pi) for p in v]
    with open(path,'w') as o:
        o.write('ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n'%(len(v),len(f)))
        for p,t in zip(v,uv): o.write('%g %g %g %g %g %g %g %g\n'%(p+p+t))
        for a,b,c in f: o.write('3 %d %d %d\n'%(a,b,c))
def grid(n, spacing):
    random.seed(1); out=[]
    for i in range(n):
        x=(i%int(math.ceil(math.sqrt(n))))*spacing; z=(i//int(math.ceil(math.sqrt(n))))*spacing
        out.append({"translate":[x,0,-z],"rotate":[0,1,0,round(random.uniform(0,360),1)],"scale":round(random.uniform(0.8,1.2),3)})
    return out
def scene(objs, n, spacing):
    side=math.ceil(math.sqrt(n))*spacing
    return {"version":1,"camera":{"from":[side/2, side*0.6, side*0.4+3],"to":[side/2,0,-side/2],"fov":50},
      "environment":{"color":[0.5,0.6,0.8]},"render":{"width":256,"height":192,"spp":4,"max_bounces":3},
      "materials":{"ground":{"type":"lambert","base_color":[0.4,0.4,0.35]},"m":{"base_color":[0.7,0.5,0.4],"roughness":0.5}},
      "objects":[{"type":"sphere","center":[0,-1000.6,0],"radius":1000,"material":"ground"}]+objs}
kind, n = sys.argv[1], int(sys.argv[2]); arg = sys.argv[3] if len(sys.argv)>3 else None
if kind=='sdf':
    o={"type":"sdf","shape":"noisy_sphere","resolution":int(arg or 128),"storage":"sparse","material":"m","instances":grid(n,2.5)}
    sc=scene([o],n,2.5)
elif kind=='disp':
    ply('/tmp/inst15/ico.ply', 4); png('/tmp/inst15/disp.png', 512, 256, lambda x,y: 0.5+0.25*math.sin(40*x)*math.sin(30*y)+0.25*math.sin(7*x+3*y))
    o={"type":"displaced","mesh":"/tmp/inst15/ico.ply","displacement":"/tmp/inst15/disp.png","scale":0.1,"offset":-0.05,"level":int(arg or 3),"material":"m","instances":grid(n,2.5)}
    sc=scene([o],n,2.5)
elif kind=='spheres':
    random.seed(2); k=int(arg or 200)
    o={"type":"spheres","material":"m","centers":[[round(random.uniform(-1,1),4),round(random.uniform(0,1),4),round(random.uniform(-1,1),4)] for _ in range(k)],"radius":0.03,"instances":grid(n,2.5)}
    sc=scene([o],n,2.5)
elif kind=='curves':
    o={"type":"curves","material":"m","basis":"bspline","children":int(arg or 60),"child_radius":0.3,"seed":3,
       "strands":[[[0,-0.05,0,0.01],[0,0,0,0.01],[0.05,0.3,0.02,0.008],[0.12,0.6,0.04,0.006],[0.24,0.84,0.06,0.002],[0.36,0.96,0.08,0]]],"instances":grid(n,2.5)}
    sc=scene([o],n,2.5)
json.dump(sc, open('/tmp/inst15/%s_%d.json'%(kind,n),'w'), indent=1)
