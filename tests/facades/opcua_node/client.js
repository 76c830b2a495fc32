// node-opcua's client, as an OPC UA client nobody on devsim wrote (tests/facades/test_opcua.py).
// Usage: node client.js ENDPOINT 'PLAN'  -- PLAN is a JSON list of steps (below); or node client.js --serve,
// which reads a plan a line from stdin as {"endpoint": ..., "plan": PLAN} and answers each with a
// line "RESULT {json}" or "FAILED "stack"" (node-opcua's start-up costs seconds of CPU: the tests
// keep one client process).  The steps, each one of
//   {"op": "browse", "node": "x"}                       browse names of the node's children
//   {"op": "browses", "items": [{"node": "x", "referenceTypeId": "i=33"}, ...], "view": "i=85"}   one Browse
//     request (forward, subtypes included; "view" a ViewId, default none): each result's status, or {"fault": name}
//   {"op": "read", "node": "x.axis.position"}           value, data type name, status
//   {"op": "write", "node": "x.param.V", "type": "Double", "value": 12.5}   status
//     both may name an "attribute" (AccessLevel, DisplayName ...; default Value) and an
//     "indexRange" ("0:2"); a read a "maxAge" (a refused request: {"fault": name}; node-opcua
//     asks for both timestamps, "timestamps" says which came) and an "encoding" (a dataEncoding
//     name), a write a "statusCode" (a StatusCodes name) to write with the value
//   {"op": "writes", "items": [["x.param.V", "Int32", 3], ...]}   one Write request, a status per item
//   {"op": "monitor", "nodes": ["x.axis.position", ...]}   the status of each one's first notification
//     (its value, "values", and which timestamps came, "timestamps": [source, server]); an
//     "indexRange" for every item, "timestamps" the timestampsToReturn (default Both)
//   {"op": "paged", "node": "x", "max": 5}   Browse of at most "max" references a node, then BrowseNext
//     while there is a continuation point: the size of each page and all the browse names; with
//     "release": true the first point is released instead (the results' count), then used again
//     (its status); {"op": "paged", "points": ["00ff"]}: BrowseNext of made-up points (the statuses)
//   {"op": "history", "node": "x.axis.position"}   HistoryRead of its raw values of the last hour: the status
//   {"op": "empty", "service": "read"}   a read, write, browse or call of no operations: {"fault": name}
//     or {"status": "Good"}
//   {"op": "translate", "node": "x", "path": ["axis.position"]}   TranslateBrowsePathsToNodeIds along
//     hierarchical references (names in urn:devsim): its status and the targets' node ids
//   {"op": "items", "items": [ITEM, ...], "modify": [id, ...]}   CreateMonitoredItems, one request an item:
//     the status of each ("fault:NAME" for a refused request), then ModifyMonitoredItems of those ids.
//     ITEM: {"node": "x.axis.phase"} (or "nodeId") with "attribute" (default Value), "indexRange",
//     "encoding" (a dataEncoding name), "filter" ({"type": "event"} or {"type": "datachange",
//     "deadband": "Absolute", "value": 1}), "sampling" (ms; then "revised": each revisedSamplingInterval)
//     and "queueSize" (default 1; then "queues": each revisedQueueSize).  With "modifyTo": [{"sampling": ms,
//     "queueSize": n}, ...] instead of "modify": one ModifyMonitoredItems of the created items, each to
//     those parameters (its own clientHandle and filter): "modified", a [revisedSamplingInterval,
//     revisedQueueSize] each
//   {"op": "call", "object": "x", "method": "x#Fault", "args": [["String", "power"], ["Boolean", true]]}
//   {"op": "queue", "node": "x.quantity.t", "items": [{"queueSize": 3, "discardOldest": false, "modifyTo": true}, ...],
//    "last": 32.0}   an item per ITEM of the node's Value on a subscription with publishing disabled
//     (each then modified to discardOldest "modifyTo" where it is given) and one on a published
//     subscription (the watch); prints "PAUSE" and waits for a line on stdin (the test changes the
//     value meanwhile), then for the watch to report "last", then enables publishing: "first", the
//     watch's first value, and "got", each item's notifications (as many as its queueSize) as [value, its
//     Overflow bit]
//   {"op": "events", "node": "x", "items": [{"queueSize": 2, "discardOldest": false}, ...], "count": 4}   an event
//     item per ITEM of the node on a subscription with publishing disabled and one on a published
//     subscription (the watch), each selecting EventId, EventType, SourceNode and SourceName;
//     prints "PAUSE" (the test sends "count" events meanwhile), waits for the watch to report them,
//     enables publishing and, when the first queued event came, prints "PAUSE" again (the test sends
//     one more event): "watched", the watch's EventIds (hex), and "got", each item's events up to
//     that last one as [EventId, EventType, SourceNode, SourceName]
// A step may name a node id in full ("nodeId": "ns=0;i=2253") instead of a devsim "node".
// String node ids are in the namespace urn:devsim.  Prints one line "RESULT {json}" (node-opcua
// writes its own warnings to stdout too).
"use strict";
const {
    OPCUAClient, AttributeIds, BrowseDirection, BrowseRequest, ClientMonitoredItem, ClientSubscription, DataChangeFilter,
    DataChangeTrigger, DataType, DeadbandType, EventFilter, MonitoringMode, StatusCodes, TimestampsToReturn,
    VariantArrayType, ViewDescription,
} = require("node-opcua-client");

function plain(value, dataType) {
    if ((dataType === DataType.Int64 || dataType === DataType.UInt64) && Array.isArray(value)) {
        return value[0] * 4294967296 + (value[1] >>> 0);  // node-opcua's [high, low] words
    }
    return ArrayBuffer.isView(value) ? Array.from(value) : value;  // (a typed array: a JSON list)
}

function wire(dataType, value) {
    if ((dataType === DataType.Double || dataType === DataType.Float) && typeof value === "string") {
        return Number(value);  // "NaN", "Infinity", "-Infinity": numbers JSON cannot carry
    }
    if ((dataType === DataType.Int64 || dataType === DataType.UInt64) && typeof value === "number") {
        return [Math.floor(value / 4294967296), value >>> 0];  // node-opcua's [high, low] words
    }
    return value;
}

function filter(spec) {
    if (!spec) {
        return null;
    }
    if (spec.type === "event") {  // the Message of every event
        return new EventFilter({ selectClauses: [{ typeDefinitionId: "i=2041", browsePath: [{ name: "Message" }],
                                                   attributeId: AttributeIds.Value }] });
    }
    return new DataChangeFilter({ trigger: DataChangeTrigger.StatusValue, deadbandType: DeadbandType[spec.deadband],
                                  deadbandValue: spec.value });
}

async function fault(request) {  // a status, or the service fault that refused the whole request
    try {
        return await request();
    } catch (err) {
        const header = err.response && err.response.responseHeader;
        if (!header) {
            throw err;
        }
        return { fault: header.serviceResult.name };
    }
}

function variant(type, value) {
    const dataType = DataType[type];
    return { dataType, arrayType: VariantArrayType.Scalar, value: wire(dataType, value) };
}

let input = null;  // the lines of stdin: the plans of --serve and the lines a pause waits for

function nextLine() {  // the next line of stdin (undefined at its end)
    if (input === null) {
        input = require("readline").createInterface({ input: process.stdin })[Symbol.asyncIterator]();
    }
    return input.next().then((next) => (next.done ? undefined : next.value));
}

async function paused() {  // "PAUSE" out, then a line in
    process.stdout.write("PAUSE\n");
    await nextLine();
}

async function within(promise, what) {  // the promise, or an error after 10 s
    let timer = null;
    const late = new Promise((resolve, reject) => { timer = setTimeout(() => reject(new Error(what())), 10000); });
    try {
        return await Promise.race([promise, late]);
    } finally {
        clearTimeout(timer);
    }
}

async function queued(session, devsim, s) {
    const options = { requestedPublishingInterval: 20, requestedLifetimeCount: 1000, requestedMaxKeepAliveCount: 10 };
    const watch = await session.createSubscription2({ ...options, publishingEnabled: true });
    const held = await session.createSubscription2({ ...options, publishingEnabled: false });
    const node = { nodeId: devsim(s.node), attributeId: AttributeIds.Value };
    const watched = [];
    let seen = null;
    const last = new Promise((resolve) => { seen = resolve; });
    const watcher = ClientMonitoredItem.create(watch, node, { samplingInterval: 0, queueSize: 10, discardOldest: true });
    watcher.on("changed", (dv) => {
        watched.push(dv.value.value);
        if (dv.value.value === s.last) {
            seen();
        }
    });
    const got = s.items.map(() => []);
    const total = s.items.reduce((sum, item) => sum + item.queueSize, 0);
    let all = null;
    const complete = new Promise((resolve) => { all = resolve; });
    for (const [index, item] of s.items.entries()) {
        const monitored = ClientMonitoredItem.create(held, node, {
            samplingInterval: 0, queueSize: item.queueSize, discardOldest: item.discardOldest });
        monitored.on("changed", (dv) => {
            got[index].push([dv.value.value, dv.statusCode.hasOverflowBit]);
            if (got.reduce((sum, values) => sum + values.length, 0) === total) {
                all();
            }
        });
        await new Promise((resolve) => monitored.once("initialized", resolve));
        if (item.modifyTo !== undefined) {
            await monitored.modify({ samplingInterval: 0, queueSize: item.queueSize, discardOldest: item.modifyTo });
        }
    }
    await paused();
    await within(last, () => `the watch never saw ${s.last}: ${watched}`);
    await held.setPublishingMode(true);
    await within(complete, () => `not every notification came: ${JSON.stringify(got)}`);
    await held.terminate();
    await watch.terminate();
    return { first: watched[0], got };
}

function seen() {  // what came, and a promise of the moment a predicate of it holds
    const items = [];
    let wake = () => {};
    return {
        items,
        push(item) {
            items.push(item);
            wake();
        },
        until(holds, what) {
            return within(new Promise((resolve) => {
                wake = () => { if (holds(items)) { resolve(); } };
                wake();
            }), () => `${what}: ${JSON.stringify(items)}`);
        },
    };
}

async function eventQueues(session, devsim, s) {
    const options = { requestedPublishingInterval: 20, requestedLifetimeCount: 1000, requestedMaxKeepAliveCount: 10 };
    const watch = await session.createSubscription2({ ...options, publishingEnabled: true });
    const held = await session.createSubscription2({ ...options, publishingEnabled: false });
    const node = { nodeId: devsim(s.node), attributeId: AttributeIds.EventNotifier };
    const eventFilter = new EventFilter({ selectClauses: ["EventId", "EventType", "SourceNode", "SourceName"].map(
        (name) => ({ typeDefinitionId: "i=2041", browsePath: [{ name }], attributeId: AttributeIds.Value })) });
    const row = (fields) => [fields[0].value.toString("hex"), fields[1].value.toString(), fields[2].value.toString(),
                             fields[3].value];
    async function item(subscription, queueSize, discardOldest, got) {
        const monitored = ClientMonitoredItem.create(subscription, node, {
            samplingInterval: 0, queueSize, discardOldest, filter: eventFilter });
        monitored.on("changed", (fields) => got(row(fields)));
        await new Promise((resolve) => monitored.once("initialized", resolve));
    }
    const watched = seen();
    await item(watch, 10, true, (fields) => watched.push(fields[0]));
    const got = s.items.map(() => []);
    const all = seen();
    for (const [index, it] of s.items.entries()) {
        await item(held, it.queueSize, it.discardOldest, (fields) => {
            got[index].push(fields);
            all.push(fields[0]);
        });
    }
    await paused();
    await watched.until((ids) => ids.length >= s.count, "the watch never saw them all");
    await held.setPublishingMode(true);
    await all.until((ids) => ids.length > 0, "nothing queued came");
    await paused();
    await watched.until((ids) => ids.length > s.count, "the watch never saw the last one");
    const last = watched.items[s.count];
    await all.until((ids) => ids.filter((id) => id === last).length === s.items.length, "the last one never came");
    await held.terminate();
    await watch.terminate();
    return { watched: watched.items, got };
}

async function step(session, ns, s) {
    const devsim = (name) => `ns=${ns};s=${name}`;
    const id = (name) => (name === undefined ? s.nodeId : devsim(name));
    if (s.op === "browse") {
        const result = await session.browse(id(s.node));
        return { status: result.statusCode.name, names: result.references.map((r) => r.browseName.name) };
    }
    if (s.op === "browses") {
        const request = new BrowseRequest({
            view: new ViewDescription({ viewId: s.view }), requestedMaxReferencesPerNode: 0,
            nodesToBrowse: s.items.map((item) => ({
                nodeId: item.node === undefined ? item.nodeId : devsim(item.node), referenceTypeId: item.referenceTypeId,
                browseDirection: BrowseDirection.Forward, includeSubtypes: true, nodeClassMask: 0, resultMask: 63,
            })),
        });
        const response = await fault(() => new Promise((resolve, reject) => {
            session.performMessageTransaction(request, (err, answer) => (err ? reject(err) : resolve(answer)));
        }));
        return response.fault ? response : { statuses: response.results.map((r) => r.statusCode.name) };
    }
    if (s.op === "paged") {
        if (s.points) {
            const made = await fault(() => session.browseNext(s.points.map((hex) => Buffer.from(hex, "hex")), false));
            return made.fault ? made : { statuses: made.map((r) => r.statusCode.name) };
        }
        const before = session.requestedMaxReferencesPerNode;
        session.requestedMaxReferencesPerNode = s.max;
        try {
            let result = await session.browse(id(s.node));
            const pages = [result.references.length];
            const names = result.references.map((r) => r.browseName.name);
            if (s.release) {
                const released = await session.browseNext([result.continuationPoint], true);
                const again = await session.browseNext(result.continuationPoint, false);
                return { pages, released: released.length, again: again.statusCode.name };
            }
            while (result.continuationPoint && result.continuationPoint.length) {
                result = await session.browseNext(result.continuationPoint, false);
                pages.push(result.references.length);
                names.push(...result.references.map((r) => r.browseName.name));
            }
            return { status: result.statusCode.name, pages, names };
        } finally {
            session.requestedMaxReferencesPerNode = before;
        }
    }
    if (s.op === "history") {
        const end = new Date();
        const result = await session.readHistoryValue(id(s.node), new Date(end.getTime() - 3600000), end);
        return { status: result.statusCode.name };
    }
    if (s.op === "empty") {
        const sent = await fault(() => session[s.service]([]));
        return sent.fault ? sent : { status: "Good" };
    }
    if (s.op === "translate") {
        const result = await session.translateBrowsePath({
            startingNode: id(s.node),
            relativePath: { elements: s.path.map((name) => ({
                referenceTypeId: "i=33", isInverse: false, includeSubtypes: true, targetName: { namespaceIndex: ns, name },
            })) },
        });
        return { status: result.statusCode.name, targets: (result.targets || []).map((t) => t.targetId.toString()) };
    }
    if (s.op === "read") {
        let dv;
        try {
            dv = await session.read({
                nodeId: id(s.node), attributeId: AttributeIds[s.attribute || "Value"], indexRange: s.indexRange,
                dataEncoding: s.encoding ? { name: s.encoding } : undefined,
            }, s.maxAge);
        } catch (err) {  // a service fault: the whole request refused
            const header = err.response && err.response.responseHeader;
            if (!header) {
                throw err;
            }
            return { fault: header.serviceResult.name };
        }
        const type = dv.value.dataType;
        return {
            status: dv.statusCode.name, type: DataType[type], value: plain(dv.value.value, type),
            timestamps: [dv.sourceTimestamp !== null, dv.serverTimestamp !== null],
        };
    }
    if (s.op === "write") {
        const value = { value: variant(s.type, s.value) };
        if (s.statusCode) {
            value.statusCode = StatusCodes[s.statusCode];
        }
        const status = await session.write({
            nodeId: id(s.node), attributeId: AttributeIds[s.attribute || "Value"], indexRange: s.indexRange, value,
        });
        return { status: status.name };
    }
    if (s.op === "writes") {
        const statuses = await session.write(s.items.map(([node, type, value]) => ({
            nodeId: devsim(node), attributeId: AttributeIds.Value, value: { value: variant(type, value) },
        })));
        return { statuses: statuses.map((status) => status.name) };
    }
    if (s.op === "monitor") {
        const subscription = ClientSubscription.create(session, {
            requestedPublishingInterval: 20, requestedLifetimeCount: 100, requestedMaxKeepAliveCount: 10,
            publishingEnabled: true,
        });
        const firsts = s.nodes.map((name) => new Promise((resolve, reject) => {
            const item = ClientMonitoredItem.create(subscription, {
                nodeId: devsim(name), attributeId: AttributeIds.Value, indexRange: s.indexRange,
            }, { samplingInterval: 0, queueSize: 1, discardOldest: true }, TimestampsToReturn[s.timestamps || "Both"]);
            const timer = setTimeout(() => reject(new Error(`no notification for ${name}`)), 10000);
            item.once("changed", (dv) => {
                clearTimeout(timer);
                resolve([dv.statusCode.name, plain(dv.value.value, dv.value.dataType),
                         [dv.sourceTimestamp !== null, dv.serverTimestamp !== null]]);
            });
        }));
        const firstValues = await Promise.all(firsts);
        await subscription.terminate();
        return { statuses: firstValues.map(([status]) => status), values: firstValues.map(([, value]) => value),
                 timestamps: firstValues.map(([, , stamps]) => stamps) };
    }
    if (s.op === "items") {
        const subscription = await session.createSubscription2({
            requestedPublishingInterval: 20, requestedLifetimeCount: 100, requestedMaxKeepAliveCount: 10,
            publishingEnabled: true,
        });
        const statuses = [];
        const revised = [];
        const queues = [];
        const ids = [];
        for (const [index, item] of s.items.entries()) {
            const created = await fault(() => session.createMonitoredItems({
                subscriptionId: subscription.subscriptionId, timestampsToReturn: TimestampsToReturn.Both,
                itemsToCreate: [{
                    itemToMonitor: {
                        nodeId: item.node === undefined ? item.nodeId : devsim(item.node), attributeId: AttributeIds[item.attribute || "Value"],
                        indexRange: item.indexRange, dataEncoding: item.encoding ? { name: item.encoding } : undefined,
                    },
                    monitoringMode: MonitoringMode.Reporting,
                    requestedParameters: { clientHandle: index + 1, samplingInterval: item.sampling || 0,
                                           queueSize: item.queueSize === undefined ? 1 : item.queueSize,
                                           discardOldest: true, filter: filter(item.filter) },
                }],
            }));
            statuses.push(created.fault ? `fault:${created.fault}` : created.results[0].statusCode.name);
            revised.push(created.fault ? null : created.results[0].revisedSamplingInterval);
            queues.push(created.fault ? null : created.results[0].revisedQueueSize);
            ids.push(created.fault ? null : created.results[0].monitoredItemId);
        }
        if (s.modifyTo) {
            const changed = await session.modifyMonitoredItems({
                subscriptionId: subscription.subscriptionId, timestampsToReturn: TimestampsToReturn.Both,
                itemsToModify: s.modifyTo.map((to, index) => ({
                    monitoredItemId: ids[index],
                    requestedParameters: { clientHandle: index + 1, samplingInterval: to.sampling, queueSize: to.queueSize,
                                           discardOldest: true, filter: filter(s.items[index].filter) },
                })),
            });
            await subscription.terminate();
            return { statuses, revised, queues,
                     modified: changed.results.map((r) => [r.revisedSamplingInterval, r.revisedQueueSize]) };
        }
        if (!s.modify) {
            await subscription.terminate();
            if (s.items.some((item) => item.queueSize !== undefined)) {
                return { statuses, revised, queues };
            }
            return s.items.some((item) => item.sampling !== undefined) ? { statuses, revised } : { statuses };
        }
        const modified = await fault(() => session.modifyMonitoredItems({
            subscriptionId: subscription.subscriptionId, timestampsToReturn: TimestampsToReturn.Both,
            itemsToModify: s.modify.map((monitoredItemId) => ({
                monitoredItemId, requestedParameters: { clientHandle: 99, samplingInterval: 0, queueSize: 1 },
            })),
        }));
        await subscription.terminate();
        return { statuses, modified: modified.fault ? `fault:${modified.fault}` : modified.results.map((r) => r.statusCode.name) };
    }
    if (s.op === "queue") {
        return queued(session, devsim, s);
    }
    if (s.op === "events") {
        return eventQueues(session, devsim, s);
    }
    if (s.op === "call") {
        const result = await session.call({
            objectId: devsim(s.object), methodId: devsim(s.method),
            inputArguments: s.args.map(([type, value]) => variant(type, value)),
        });
        return { status: result.statusCode.name,
                 inputs: (result.inputArgumentResults || []).map((status) => status.name) };
    }
    throw new Error(`unknown step ${s.op}`);
}

async function run(endpoint, plan) {  // one plan on a session of its own: { namespace, results }
    const client = OPCUAClient.create({ endpointMustExist: false, connectionStrategy: { maxRetry: 0 } });
    await client.connect(endpoint);
    try {
        const session = await client.createSession();
        const namespaces = await session.readNamespaceArray();
        const ns = namespaces.indexOf("urn:devsim");
        const results = [];
        for (const s of plan) {
            results.push(await step(session, ns, s));
        }
        await session.close();
        return { namespace: ns, results };
    } finally {
        await client.disconnect();
    }
}

async function serve() {  // --serve: a line {"endpoint": ..., "plan": [...]} at a time on stdin
    for (let line = await nextLine(); line !== undefined; line = await nextLine()) {
        let answer;
        try {
            const { endpoint, plan } = JSON.parse(line);
            answer = `RESULT ${JSON.stringify(await run(endpoint, plan))}`;
        } catch (err) {
            answer = `FAILED ${JSON.stringify(String(err.stack || err))}`;
        }
        process.stdout.write(`${answer}\n`);
    }
}

async function main() {
    if (process.argv[2] === "--serve") {
        return serve();
    }
    const [endpoint, planText] = process.argv.slice(2);
    const result = await run(endpoint, JSON.parse(planText));
    process.stdout.write(`RESULT ${JSON.stringify(result)}\n`);
}

// (exit at once: node-opcua keeps the process alive some 2 s after its client disconnected; a
// write to a pipe is synchronous on Linux, so the RESULT line is out)
main().then(() => process.exit(0), (err) => {
    process.stderr.write(`${err.stack || err}\n`);
    process.exit(1);
});
