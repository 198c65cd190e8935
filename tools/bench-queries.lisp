;;;; tools/bench-queries.lisp -- rays, sphere casts and region queries against the basin (make bench).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(funcall (find-symbol "RUN-QUERY-BENCHMARK" '#:luv-physics))
