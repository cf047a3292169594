// Long soak (not part of `node --test`): node soak.mjs [seconds=600] against SEAARMS_URL or a
// server started by the harness. Prints heap and frame rates every 30 s and a summary.
import { server, soak } from './harness.mjs';
const seconds = +(process.argv[2] || 600);
const url = await server();
const r = await soak(url, seconds, { log: (s) => console.log(JSON.stringify({ t: new Date(s.t).toISOString(), heapMB: +s.heapMB.toFixed(2), nodes: s.nodes, received: s.received, drawn: s.drawn })) });
delete r.samples;
console.log(JSON.stringify(r, null, 1));
process.exit(0);
