;;;; tools/bench-sleeping.lisp -- what sleepers cost, at several counts (make bench).
;;;; Prints an Org table; the Makefile also writes it into physics.org.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(funcall (find-symbol "RUN-SLEEPING-SCALE-BENCHMARK" '#:luv-physics))
