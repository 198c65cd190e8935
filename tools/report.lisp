;;;; tools/report.lisp -- the stiff and extreme cases (make report).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(funcall (find-symbol "RUN-STABILITY-TABLE" '#:luv-physics))
