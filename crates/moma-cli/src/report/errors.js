// Runs first: every uncaught error, failed resource and console.error is recorded on
// <body data-errors> (and counted in data-error-count), so a headless check can read them.
(function () {
  var errs = [];
  function rec(m) {
    errs.push(String(m).slice(0, 300));
    document.body.setAttribute('data-errors', errs.join(' | '));
    document.body.setAttribute('data-error-count', String(errs.length));
  }
  window.addEventListener('error', function (e) {
    rec('error: ' + (e.message || (e.target && (e.target.src || e.target.href)) || 'unknown'));
  }, true);
  window.addEventListener('unhandledrejection', function (e) { rec('unhandled rejection: ' + e.reason); });
  var ce = console.error;
  console.error = function () {
    rec('console.error: ' + Array.prototype.map.call(arguments, String).join(' '));
    return ce.apply(console, arguments);
  };
})();
