// A part of the feature table in a thread of its own: the page splits the vertices between
// itself and these workers, so that a click's metric runs on every core (metrics.js).
import { computeMetric } from './metrics.js';

let table = null;

self.onmessage = ({ data }) => {
  if (data.table) {
    table = data.table; // rows of the table, as featureTable() makes them
    return;
  }
  const { reference, name, p, inverseVariances } = data;
  const out = new Float32Array(table.n), shown = new Float32Array(table.n);
  try {
    const undefinedCount = computeMetric(table, reference, name, p, out, shown, { inverseVariances });
    self.postMessage({ out, shown, undefinedCount }, [out.buffer, shown.buffer]);
  } catch (e) {
    self.postMessage({ error: e.message });
  }
};
