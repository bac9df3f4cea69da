import json,glob,statistics as st
def load(f):
    try: return json.load(open(f))['scenes'][0]
    except Exception: return None
for t in ['sph','sdf','crv','disp']:
    rows=[]
    for i in range(1,4):
        o,n=load(f'{t}_old{i}.json'),load(f'{t}_new{i}.json')
        if not o or not n: continue
        r={}
        for a,b in zip(o['ray_sets'],n['ray_sets']):
            r[a['name']]=b['mrays_kernel']/a['mrays_kernel']
            if a.get('embree_mrays'): r[a['name']+'/E']=(b['mrays_kernel']/b['embree_mrays'])/(a['mrays_kernel']/a['embree_mrays'])
        r['path']=n['path_mrays']/o['path_mrays']
        r['inst']=(o['instances'],n['instances'])
        rows.append(r)
    if not rows: continue
    print(t, len(rows), 'pairs')
    for k in rows[0]:
        if k=='inst': print('  instances old,new', [r[k] for r in rows]); continue
        v=[r[k] for r in rows]; print('  %-12s median %.2f  (%s)'%(k, st.median(v), ', '.join('%.2f'%x for x in v)))
