;;;; tools/report.lisp -- make report: the stiff and extreme cases (REPORT=stability) or the
;;;; error-against-run-time sweep (REPORT=accuracy), which writes its tables and SVG diagrams
;;;; under report/.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(let ((part (uiop:getenv "REPORT")))
  (cond ((equal part "stability")
         (funcall (find-symbol "RUN-STABILITY-TABLE" '#:luv-physics)))
        ((equal part "heaps")
         (funcall (find-symbol "RUN-HEAP-TABLE" '#:luv-physics)))
        ((equal part "accuracy")
         (funcall (find-symbol "RUN-ACCURACY-REPORT" '#:luv-physics) :directory "report/"))
        (t (format *error-output* "report: set REPORT to stability, heaps or accuracy~%")
           (sb-ext:exit :code 2))))
