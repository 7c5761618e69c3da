"""Tables of bench/budget_sweep.sh: exact SAH over flat's by budget factor, per rule."""
import json, sys, os
d = sys.argv[1]
order = ['default','fzk_haus','two_cylinder_engine','cg57_cruiser','brainstem','motion_capture_rom','trees2k','crown','powerplant','city']
fs = [1,2,4,8,16,32,64]
for rule, prefix, prims in [('paper', 'rebraid:opening=extent:bref-bounds=box:budget-factor=', 'rebraid:opening=extent:bref-bounds=box:budget-rule=primitives'), ('default (sah + vertices)', 'rebraid:budget-factor=', 'rebraid:budget-rule=primitives')]:
    print(f'\n#### SAH / flat SAH by budget factor, {rule} rules\n')
    hdr = ['scene','instances','twolevel'] + [f'B={f}' for f in fs] + ['primitives / 1000 (budget)'] + (['search from 4 (budget)'] if rule.startswith('default') else [])
    print('| ' + ' | '.join(hdr) + ' |'); print('|' + '---|'*len(hdr))
    for n in order:
        rows = {r['accel']: r for r in json.load(open(f'{d}/{n}.json'))}
        fl = rows['flat']['sah']
        cells = [n, str(rows['twolevel']['instances']), f"{rows['twolevel']['sah']/fl:.3f}"]
        best = min(rows[prefix + str(f)]['sah'] for f in fs)
        for f in fs:
            x = rows[prefix + str(f)]['sah']
            cells.append(f"**{x/fl:.3f}**" if x == best else f"{x/fl:.3f}")
        r = rows[prims]; cells.append(f"{r['sah']/fl:.3f} ({r['budget']})")
        if rule.startswith('default'):
            r = rows['rebraid:budget-doublings=4']; cells.append(f"{r['sah']/fl:.3f} ({r['budget']})")
        print('| ' + ' | '.join(cells) + ' |')
