// roslibjs (npm "roslib", in Node) doing what roslibjs's own examples and tests do, against
// rbd_bridge. Prints one JSON line with what each step saw; the pytest judges it.
// Usage: node roslibjs_examples.js ws://127.0.0.1:PORT examples|png|service
'use strict';
const ROSLIB = require('roslib');

const [url, mode] = process.argv.slice(2);
const result = {};
const ros = new ROSLIB.Ros({ url: url });
const fail = (why) => { console.log(JSON.stringify({ error: String(why), partial: result })); process.exit(1); };
setTimeout(() => fail('timeout'), 90000);
ros.on('error', (e) => fail('connection error ' + (e && e.message)));

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
const topic = (name, type, extra) => new ROSLIB.Topic(Object.assign({ ros: ros, name: name, messageType: type }, extra));
const getTopics = () => new Promise((resolve, reject) => ros.getTopics((r) => resolve(r.topics), reject));
const getServices = () => new Promise((resolve, reject) => ros.getServices(resolve, reject));
// Poll an (async) condition until it holds or `ms` pass; its last value (this script's wait_for).
async function until(pred, ms) {
  const end = Date.now() + ms;
  for (;;) {
    const value = await pred();
    if (value || Date.now() >= end) { return value; }
    await sleep(50);
  }
}

// pubsub.example: two Topic objects on one topic and one connection; the very first publish
// (an implicit advertise) must reach the other object's subscription through ROS.
async function pubsub() {
  const example = topic('/example_topic', 'std_msgs/String');
  const example2 = topic('/example_topic', 'std_msgs/String');
  const seen = [];
  await new Promise((resolve) => {
    example2.subscribe((m) => { seen.push(m.data); if (seen.length === 1) { resolve(); } });
    example.publish({ data: 'Hello Example2!' });
    setTimeout(resolve, 3000);
  });
  example.unadvertise();
  example2.unsubscribe();
  result.pubsub_first = seen;
}

// topic-listener.example: publish 1..4 every 50 ms right after subscribing; all four, in order.
async function listener() {
  const t = topic('/echo/test', 'std_msgs/String');
  const seen = [];
  const four = new Promise((resolve) => {
    t.subscribe((m) => { seen.push(m.data); if (seen.length === 4) { resolve(); } });
    setTimeout(resolve, 10000);
  });
  for (const data of ['1', '2', '3', '4']) {
    await sleep(50);
    t.publish({ data: data });
  }
  await four;
  t.unsubscribe();
  t.unadvertise();
  result.listener = seen;
}

// params.examples: set, get, getParams, delete.
async function params() {
  const p = new ROSLIB.Param({ ros: ros, name: '/test/foo' });
  await new Promise((resolve) => p.set('bar', resolve));
  result.param_get = await new Promise((resolve) => p.get(resolve));
  const listed = await new Promise((resolve) => ros.getParams(resolve));
  await new Promise((resolve) => p.delete(resolve));
  const after = await new Promise((resolve) => ros.getParams(resolve));
  result.param_listed = listed.includes('/test/foo');
  result.param_listed_after_delete = after.includes('/test/foo');
}

// fibonacci.example: the goal is sent 100 ms after the ActionClient advertised its topics.
async function fibonacci() {
  const client = new ROSLIB.ActionClient({ ros: ros, serverName: '/fibonacci', actionName: 'actionlib_tutorials/FibonacciAction' });
  const goal = new ROSLIB.Goal({ actionClient: client, goalMessage: { order: 7 } });
  const feedback = [];
  goal.on('feedback', (f) => feedback.push(f.sequence));
  const done = new Promise((resolve) => goal.on('result', resolve));
  setTimeout(() => goal.send(), 100);
  const res = await Promise.race([done, sleep(15000).then(() => null)]);
  result.fibonacci_result = res && res.sequence;
  result.fibonacci_feedback = feedback;
  client.dispose();
}

// check-topics.example: advertise lists the topic, unadvertise ends it.
async function checkTopics() {
  const t = topic('/some_test_topic', 'std_msgs/String');
  result.topic_before = (await getTopics()).includes('/some_test_topic');
  const listed = async () => (await getTopics()).includes('/some_test_topic');
  t.advertise();
  result.topic_advertised = await until(listed, 10000);
  t.unadvertise();
  result.topic_after_unadvertise = !(await until(async () => !(await listed()), 10000));
}

// compression 'png' (roslibjs decodes the PNG and JSON.parses the pixels as text: its own
// callback throws, and ends the process, when the padding is not whitespace).
async function png() {
  const out = topic('/echo/out', 'std_msgs/String', { compression: 'png' });
  const inp = topic('/echo/in', 'std_msgs/String');
  result.png = await new Promise((resolve) => {
    const timer = setInterval(() => inp.publish({ data: 'through a png' }), 100);
    out.subscribe((m) => { clearInterval(timer); out.unsubscribe(); resolve(m.data); });
    setTimeout(() => { clearInterval(timer); resolve(null); }, 10000);
  });
  inp.unadvertise();
}

// service.test.js of roslibjs: a service is advertised, called, unadvertised, and advertised
// again under the same name by a new Service object; each call must reach the provider of
// its time. roslib 1.4.1's unadvertise leaves the old object's request listener on `ros`
// (later roslibjs releases remove it): it is removed here, so only the bridge is judged.
async function service() {
  const name = '/roslibjs_test_service';
  const call = () => new Promise((resolve) => {
    const client = new ROSLIB.Service({ ros: ros, name: name, serviceType: 'std_srvs/Trigger' });
    client.callService(new ROSLIB.ServiceRequest({}), resolve, (err) => resolve('error: ' + err));
  });
  result.service = [];
  for (const message of ['first provider', 'second provider']) {
    const server = new ROSLIB.Service({ ros: ros, name: name, serviceType: 'std_srvs/Trigger' });
    server.advertise((req, resp) => { resp.success = true; resp.message = message; return true; });
    await until(async () => (await getServices()).includes(name), 10000);  // registered with ROS
    result.service.push(await call());
    server.unadvertise();
    ros.removeAllListeners(name);
  }
}

const MODES = { png: [png], service: [service], examples: [pubsub, listener, params, fibonacci, checkTopics] };

ros.on('connection', async () => {
  try {
    for (const step of MODES[mode]) {
      await step();
    }
    console.log(JSON.stringify(result));
    ros.close();
    process.exit(0);
  } catch (e) {
    fail(e && e.stack ? e.stack : e);
  }
});
