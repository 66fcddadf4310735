#!/usr/bin/env python3
"""Lengths of C++ function bodies, by brace matching (a heuristic: macros and odd formatting can
fool it). Usage: python3 scripts/function-lengths.py MIN_LINES DIR...; prints the longest first."""
import re, sys, os
MIN=int(sys.argv[1])
def strip(line, state):
    out=[];i=0
    while i<len(line):
        if state['block']:
            j=line.find('*/',i)
            if j<0: return ''.join(out)
            state['block']=False; i=j+2; continue
        c=line[i]
        if line.startswith('//',i): break
        if line.startswith('/*',i): state['block']=True; i+=2; continue
        if c=='"' or c=="'":
            q=c; i+=1
            while i<len(line) and line[i]!=q:
                if line[i]=='\\': i+=1
                i+=1
            i+=1; out.append('""'); continue
        out.append(c); i+=1
    return ''.join(out)
res=[]
for root in sys.argv[2:]:
  for dp,dn,fn in os.walk(root):
    if '/build' in dp or 'fuzz/corpus' in dp: continue
    for f in fn:
        if not f.endswith(('.cpp','.h')): continue
        p=os.path.join(dp,f)
        lines=open(p,errors='replace').read().split('\n')
        state={'block':False}
        stack=[]  # entries: ('scope'|'func'|'other', start_line, name)
        pending=''
        for ln,raw in enumerate(lines,1):
            s=strip(raw,state)
            if s.strip().startswith('#'): continue
            for ch in s:
                if ch=='{':
                    head=pending.strip()
                    infunc=any(k=='func' for k,_,_ in stack)
                    kind='other'
                    if not infunc:
                        if re.search(r'\b(namespace|class|struct|enum|union)\b[^()]*$',head) or head.endswith('=') or head=='' or re.search(r'\b(extern "")\s*$',head):
                            kind='scope'
                        elif ')' in head:
                            kind='func'
                    name=''
                    if kind=='func':
                        m=re.findall(r'([A-Za-z_][\w:~<>]*)\s*\(',head)
                        name=m[0] if m else head[-40:]
                        if name in ('if','for','while','switch','catch'): kind='other'
                    stack.append((kind,ln,name)); pending=''
                elif ch=='}':
                    if stack:
                        kind,start,name=stack.pop()
                        if kind=='func' and ln-start+1>=MIN: res.append((ln-start+1,p,start,name))
                    pending=''
                elif ch==';':
                    pending=''
                else:
                    pending+=ch
            pending+=' '
for n,p,s,name in sorted(res,reverse=True): print(f"{n:4d} {p}:{s} {name}")
