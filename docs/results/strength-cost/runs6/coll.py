import timeit, numpy as np
n=65536
rng=np.random.default_rng(0)
draws=np.stack([rng.integers(j,52,n).astype(np.int8) for j in range(9)])
def coll():
    before = np.empty_like(draws); deals = np.empty_like(draws)
    for j in range(9):
        held, taken = np.full_like(draws[j], j), draws[j].copy()
        for i in range(j):
            np.copyto(held, before[i], where=draws[i] == j)
            np.copyto(taken, before[i], where=draws[i] == draws[j])
        before[j], deals[j] = held, taken
    return deals
W = np.uint64
def coll2():
    rows = draws.shape[1]
    before = np.empty_like(draws); deals = np.empty_like(draws)
    b64 = before.view(np.uint64)  # (9, rows/8)
    for j in range(9):
        if j == 0:
            before[0] = 0; deals[0] = draws[0]; continue
        # 0xFF where an earlier step drew j (held) or drew the same position (taken)
        m = np.empty((2, j, rows), dtype=np.bool_)
        np.equal(draws[:j], j, out=m[0]); np.equal(draws[:j], draws[j], out=m[1])
        masks = np.negative(m.view(np.uint8)).view(np.uint64)  # (2, j, rows/8)
        held = np.full(rows // 8, W(0x0101010101010101 * j), dtype=np.uint64)
        taken = draws[j].view(np.uint64).copy()
        for i in range(j):
            held ^= (held ^ b64[i]) & masks[0, i]
            taken ^= (taken ^ b64[i]) & masks[1, i]
        b64[j] = held; deals[j].view(np.uint64)[:] = taken
    return deals
assert (coll()==coll2()).all()
t=lambda s: min(timeit.repeat(s, number=20, repeat=5, globals=globals()))/20*1e3
print("coll ms", t("coll()"), "coll2 ms", t("coll2()"))
def coll3():
    before = np.empty_like(draws); deals = np.empty_like(draws)
    for j in range(9):
        held, taken = np.full_like(draws[j], j), draws[j].copy()
        last = j == 8
        for i in range(j):
            b = before[i]
            if not last:
                held += (b - held) * (draws[i] == j)
            taken += (b - taken) * (draws[i] == draws[j])
        before[j], deals[j] = held, taken
    return deals
def coll4():
    before = np.empty_like(draws); deals = np.empty_like(draws)
    for j in range(9):
        held, taken = np.full_like(draws[j], j), draws[j].copy()
        last = j == 8
        for i in range(j):
            if not last:
                np.copyto(held, before[i], where=draws[i] == j)
            np.copyto(taken, before[i], where=draws[i] == draws[j])
        before[j], deals[j] = held, taken
    return deals
assert (coll()==coll3()).all()
print("coll ms", t("coll()"), "coll3 ms", t("coll3()"), "coll4", t("coll4()"))
