# Exact rational-arithmetic derivation of the numbers in tests/known_answers.rs
# (one predict + compass + two-line update step). Run: python3 hand_step.py
from fractions import Fraction as F
def mat(r,c): return [[F(0)]*c for _ in range(r)]
def mul(a,b): return [[sum(a[i][k]*b[k][j] for k in range(len(b))) for j in range(len(b[0]))] for i in range(len(a))]
def T(a): return [list(r) for r in zip(*a)]
def add(a,b): return [[a[i][j]+b[i][j] for j in range(len(a[0]))] for i in range(len(a))]
def sub(a,b): return [[a[i][j]-b[i][j] for j in range(len(a[0]))] for i in range(len(a))]
def inv(m):
    n=len(m); a=[row[:]+[F(int(i==j)) for j in range(n)] for i,row in enumerate(m)]
    for c in range(n):
        p=next(r for r in range(c,n) if a[r][c]!=0); a[c],a[p]=a[p],a[c]
        pv=a[c][c]; a[c]=[v/pv for v in a[c]]
        for r in range(n):
            if r!=c: f=a[r][c]; a[r]=[a[r][j]-f*a[c][j] for j in range(2*n)]
    return [row[n:] for row in a]
I3=[[F(int(i==j)) for j in range(3)] for i in range(3)]
x=[[F(0)],[F(0)],[F(0)]]; P=[[F(1,100) if i==j else F(0) for j in range(3)] for i in range(3)]
R_,L_,dt,d=F(5,100),F(6,10),F(1,10),F(1,100); wl=wr=F(2)
ds=dt*R_*(wl+wr)/2; dth=dt*R_*(wr-wl)/L_
print("ds",ds,"dth",dth)
# theta=0, dth=0: c=1,s=0
A=[[1,0,-ds*0],[0,1,ds*1],[0,0,1]]; A=[[F(v) for v in r] for r in A]
W=[[dt*R_/2*(1-ds/L_*0), dt*R_/2*(1+ds/L_*0)],[dt*R_/2*(0+ds/L_), dt*R_/2*(0-ds/L_)],[dt*R_/L_, -dt*R_/L_]]
Q=[[d*wr*wr,F(0)],[F(0),d*wl*wl]]
x=[[x[0][0]+ds],[x[1][0]],[x[2][0]+dth]]
P=add(mul(mul(A,P),T(A)), mul(mul(W,Q),T(W)))
print("x-",[float(v[0]) for v in x]); print("P-",P)
def update(x,P,H,R,y):
    S=add(mul(mul(H,P),T(H)),R); Si=inv(S); K=mul(mul(P,T(H)),Si)
    nis=mul(mul(T(y),Si),y)[0][0]
    x=add(x,mul(K,y)); IKH=sub(I3,mul(K,H))
    P=add(mul(mul(IKH,P),T(IKH)), mul(mul(K,R),T(K)))
    return x,P,nis
# compass
x,P,nis=update(x,P,[[F(0),F(0),F(1)]],[[F(1,10000)]],[[F(2,100)-x[2][0]]])
print("after compass x",x,"nis",nis)
# line 1: rho=2,beta=0: rhat=2-x, psihat=-theta ; z=(1.985,-0.01)
y=[[F(1985,1000)-(2-x[0][0])],[F(-1,100)-(-x[2][0])]]
x,P,nis1=update(x,P,[[F(-1),F(0),F(0)],[F(0),F(0),F(-1)]],[[F(1,10000),F(2,100000)],[F(2,100000),F(4,10000)]],y)
print("nis1",nis1)
# line 2: rho=1.5, beta=pi/2: rhat=1.5-y, psihat=pi/2-theta ; z=(1.49, pi/2-0.012)
y=[[F(149,100)-(F(3,2)-x[1][0])],[F(-12,1000)+x[2][0]]]
x,P,nis2=update(x,P,[[F(0),F(-1),F(0)],[F(0),F(0),F(-1)]],[[F(2,10000),F(0)],[F(0),F(1,10000)]],y)
print("nis2",nis2)
print("x =", [repr(float(v[0])) for v in x])
print("P =", [[repr(float(v)) for v in r] for r in P])
print("nis", repr(float(nis)), repr(float(nis1)), repr(float(nis2)))
