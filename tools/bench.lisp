;;;; tools/bench.lisp -- run one of the page's benchmarks (make bench) and print its Org table;
;;;; the Makefile writes the table into physics.org.
;;;;
;;;; BENCH in the environment names the benchmark function of the luv-physics package:
;;;; run-basin-benchmark (the default), run-scene-benchmark, run-sleeping-scale-benchmark,
;;;; run-query-benchmark, run-feature-benchmark, run-against-benchmark, run-count-against,
;;;; run-count-features or run-count-pyramid.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(let* ((name (string-upcase (or (sb-ext:posix-getenv "BENCH") "run-basin-benchmark")))
       (benchmark (find-symbol name '#:luv-physics)))
  (unless (and benchmark (fboundp benchmark))
    (format *error-output* "~&bench: no benchmark ~A in luv-physics~%" name)
    (sb-ext:exit :code 2))
  (funcall benchmark))
