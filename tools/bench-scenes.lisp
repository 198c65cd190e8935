;;;; tools/bench-scenes.lisp -- the settled pile, the churning pile and the fountain (make bench).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(funcall (find-symbol "RUN-SCENE-BENCHMARK" '#:luv-physics))
