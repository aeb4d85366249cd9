#!/usr/bin/env python3
"""Direct light against the exact answer, for checking a renderer's light sampling.

    direct_check.py SCENE.json IMAGE.pfm...

SCENE: quads only, diffuse materials and one quad emitter (the classic box), a right-handed
camera, rendered at 256x256 with direct light only (trac0r --max-depth 2, render_scene.py
--max-bounces 0). For one pixel in each 4x4 block whose surface sees the whole light (its
corners and centre unshadowed), the exact radiance is albedo / pi * L * E at 4 points in the
pixel, E the irradiance of the light polygon by Lambert's formula (half the sum over the
edges of the angle each subtends times the cosine of its plane's normal with the surface
normal). Prints render / exact per surface (shape name), summed over the pixels.
"""
import json, math, os, sys
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pfmtool as P
if len(sys.argv) < 3:
    P.die("usage: direct_check.py SCENE.json IMAGE.pfm...")
S = json.load(open(sys.argv[1]))
def sub(a,b): return [a[0]-b[0],a[1]-b[1],a[2]-b[2]]
def add(a,b): return [a[0]+b[0],a[1]+b[1],a[2]+b[2]]
def mul(a,s): return [a[0]*s,a[1]*s,a[2]*s]
def dot(a,b): return a[0]*b[0]+a[1]*b[1]+a[2]*b[2]
def cross(a,b): return [a[1]*b[2]-a[2]*b[1],a[2]*b[0]-a[0]*b[2],a[0]*b[1]-a[1]*b[0]]
def norm(a): l=math.sqrt(dot(a,a)); return mul(a,1/l)
tris=[]
for sh in S['shapes']:
    v=sh['vertices']; m=sh['material']
    for t in ((v[0],v[1],v[2]),(v[0],v[2],v[3])): tris.append((t,m,sh['name']))
def hit(o,d,tmax=1e30):
    best=None
    for (a,b,c),m,n in tris:
        e1=sub(b,a); e2=sub(c,a); p=cross(d,e2); det=dot(e1,p)
        if abs(det)<1e-12: continue
        inv=1/det; s=sub(o,a); u=dot(s,p)*inv
        if u<0 or u>1: continue
        q=cross(s,e1); v=dot(d,q)*inv
        if v<0 or u+v>1: continue
        t=dot(e2,q)*inv
        if t>1e-3 and t<tmax and (best is None or t<best[0]): best=(t,m,n,norm(cross(e1,e2)))
    return best
cam=S['camera']; pos=cam['position']; d0=norm(sub(cam['look_at'],pos)); up=cam['up']
right=norm(cross(d0,up)); cu=cross(right,d0)
W=H=256; ch=2*math.tan(math.radians(cam['fov'])/2); cw=ch
em=[sh for sh in S['shapes'] if S['materials'][sh['material']]['type']=='emitter']
if len(em)!=1 or em[0]['type']!='quad' or any(sh['type']!='quad' for sh in S['shapes']):
    P.die("direct_check.py: expected quads only and exactly one quad emitter")
mat=S['materials'][em[0]['material']]
L=[c*mat['emittance'] for c in mat['color']]; light=em[0]['vertices']
light_y=min(v[1] for v in light)
alb={k:v['color'] for k,v in S['materials'].items() if v['type']=='diffuse'}
def E(x,n):
    s=0.0
    for i in range(4):
        a=norm(sub(light[i],x)); b=norm(sub(light[(i+1)%4],x))
        th=math.acos(max(-1,min(1,dot(a,b)))); g=norm(cross(a,b)); s+=th*dot(g,n)
    return abs(s)/2
lc=mul(add(add(light[0],light[1]),add(light[2],light[3])),0.25)
def visible(x):
    for p in light+[lc]:
        dd=sub(p,x); l=math.sqrt(dot(dd,dd)); h=hit(x,mul(dd,1/l),l-1e-2)
        if h and S['materials'][h[1]]['type']!='emitter': return False
    return True
imgs=[P.read_pfm(f) for f in sys.argv[2:]]
acc={}
for py in range(0,H,4):
    for px in range(0,W,4):
        vals=[]; ok=True; region=None
        for sy,sx in ((0.25,0.25),(0.25,0.75),(0.75,0.25),(0.75,0.75)):
            sxp=((px+sx)/W-0.5)*cw; syp=(0.5-(py+sy)/H)*ch
            d=norm(add(d0,add(mul(right,sxp),mul(cu,syp))))
            h=hit(pos,d)
            if not h or S['materials'][h[1]]['type']=='emitter': ok=False; break
            x=add(pos,mul(d,h[0])); n=h[3]
            if dot(n,d)>0: n=mul(n,-1)
            if x[1]>=light_y or not visible(x): ok=False; break
            e=E(x,n); vals.append([alb[h[1]][c]*L[c]*e/math.pi for c in range(3)]); region=h[2]
        if not ok: continue
        ref=[sum(v[c] for v in vals)/4 for c in range(3)]
        row=H-1-py  # PFM bottom-up
        for k,im in enumerate(imgs):
            i=(row*W+px)*3
            got=im[2][i:i+3]
            a=acc.setdefault((region,k),[0.0,0.0,0])
            a[0]+=sum(got); a[1]+=sum(ref); a[2]+=1
for (region,k),(g,r,n) in sorted(acc.items()):
    print("%-18s %s n=%4d render/analytic %.4f" % (region, sys.argv[2+k].split('/')[-1], n, g/r))
