// roslibjs (npm "roslib", run in Node) against rbd_bridge: publish/subscribe through the
// echo peer, a service call, a client-hosted service, rosapi and params.
// Usage: node roslibjs_client.js ws://127.0.0.1:PORT  -> prints one JSON line, exit 0.
'use strict';
const ROSLIB = require('roslib');

const url = process.argv[2];
const result = {};
const ros = new ROSLIB.Ros({ url: url });
const fail = (why) => { console.log(JSON.stringify({ error: String(why), partial: result })); process.exit(1); };
setTimeout(() => fail('timeout'), 30000);
ros.on('error', (e) => fail('connection error ' + (e && e.message)));

function step(name, fn) {
  return new Promise((resolve, reject) => fn((value) => { result[name] = value; resolve(value); }, reject));
}

ros.on('connection', async () => {
  try {
    await step('echo', (done) => {
      const out = new ROSLIB.Topic({ ros: ros, name: '/echo/out', messageType: 'std_msgs/String' });
      const inp = new ROSLIB.Topic({ ros: ros, name: '/echo/in', messageType: 'std_msgs/String' });
      let timer = null;
      out.subscribe((msg) => { clearInterval(timer); out.unsubscribe(); done(msg.data); });
      timer = setInterval(() => inp.publish(new ROSLIB.Message({ data: 'from roslibjs' })), 100);
    });
    await step('set_bool', (done, reject) => {
      const srv = new ROSLIB.Service({ ros: ros, name: '/echo/set_bool', serviceType: 'std_srvs/SetBool' });
      srv.callService(new ROSLIB.ServiceRequest({ data: true }), done, reject);
    });
    await step('fail', (done) => {
      const srv = new ROSLIB.Service({ ros: ros, name: '/echo/fail', serviceType: 'std_srvs/Trigger' });
      srv.callService(new ROSLIB.ServiceRequest({}), () => done('unexpected success'), (err) => done(String(err)));
    });
    await step('hosted', (done, reject) => {
      const server = new ROSLIB.Service({ ros: ros, name: '/js/negate', serviceType: 'std_srvs/SetBool' });
      server.advertise((req, resp) => { resp.success = !req.data; resp.message = 'js'; return true; });
      setTimeout(() => {
        const client = new ROSLIB.Service({ ros: ros, name: '/js/negate', serviceType: 'std_srvs/SetBool' });
        client.callService(new ROSLIB.ServiceRequest({ data: true }), done, reject);
      }, 500);
    });
    await step('topics', (done, reject) => ros.getTopics((r) => done(r), reject));
    await step('topic_type', (done, reject) => ros.getTopicType('/echo/tick', done, reject));
    await step('services', (done, reject) => ros.getServices(done, reject));
    await step('nodes', (done, reject) => ros.getNodes(done, reject));
    await step('message_details', (done, reject) => ros.getMessageDetails('std_msgs/Header', done, reject));
    await step('param', (done) => {
      const p = new ROSLIB.Param({ ros: ros, name: '/js_param' });
      p.set({ n: 42, s: 'x' }, () => p.get(done));
    });
    await step('time', (done, reject) => {
      const srv = new ROSLIB.Service({ ros: ros, name: '/rosapi/get_time', serviceType: 'rosapi/GetTime' });
      srv.callService(new ROSLIB.ServiceRequest({}), (r) => done(r.time), reject);
    });
    console.log(JSON.stringify(result));
    ros.close();
    process.exit(0);
  } catch (e) {
    fail(e);
  }
});
