#!/usr/bin/env python3
"""Lists every function of non-test Rust code over 100 lines, as (lines, file, name, line, whether a
comment above it says why it is better "whole"). Run from the repository root:
    python3 scripts/long-functions.py
Test modules (after `#[cfg(test)]`) and files named tests*.rs are left out."""
import re,sys,os
roots=['shared/src','host/src','firmware/src','host/examples','tests']
res=[]
for root in roots:
    for dp,dn,fn in os.walk(root):
        for f in fn:
            if not f.endswith('.rs'): continue
            p=os.path.join(dp,f)
            if re.search(r'(^|/)tests?(_\w+)?\.rs$',p) or '/tests/' in p: continue
            lines=open(p).read().split('\n')
            # cut at #[cfg(test)]
            cut=len(lines)
            for i,l in enumerate(lines):
                if l.startswith('#[cfg(test)]'): cut=i;break
            i=0
            while i<cut:
                l=lines[i]
                m=re.match(r'\s*(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?(extern\s+"C"\s+)?fn\s+(\w+)',l)
                if m:
                    # find opening brace
                    depth=0;started=False;j=i
                    while j<cut:
                        for ch in lines[j]:
                            if ch=='{': depth+=1;started=True
                            elif ch=='}': depth-=1
                        if started and depth==0: break
                        if not started and lines[j].rstrip().endswith(';'): break
                        j+=1
                    n=j-i+1
                    if started and n>100:
                        # comment above?
                        k=i-1
                        while k>=0 and lines[k].strip().startswith('#['): k-=1
                        doc=[]
                        while k>=0 and (lines[k].strip().startswith('//')): doc.append(lines[k]);k-=1
                        why=any('whole' in d.lower() for d in doc)
                        res.append((n,p,m.group(6),i+1,why))
                    i=j+1 if started else i+1
                else: i+=1
for r in sorted(res, reverse=True):
    print(r)
if not res:
    print('no function over 100 lines')
