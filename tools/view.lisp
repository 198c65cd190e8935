;;;; tools/view.lisp -- record a standard scene and write its viewer (make view SCENE=basin).
;;;; Environment: SCENE (basin, pile, fountain, lava, player; default basin), EVERY (steps a
;;;; frame, default 2), VIEW (the file to write, default report/view-SCENE.html).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics")
  (sb-ext:exit :code 2))

(let* ((scenes (symbol-value (find-symbol "*PHYSICS-SCENES*" '#:luv-physics)))
       (name (string-upcase (or (sb-ext:posix-getenv "SCENE") "basin")))
       (entry (find name scenes :key (lambda (e) (symbol-name (first e))) :test #'string=))
       (every (parse-integer (or (sb-ext:posix-getenv "EVERY") "2")))
       (out (or (sb-ext:posix-getenv "VIEW") (format nil "report/view-~(~A~).html" name))))
  (unless entry
    (format *error-output* "view: no scene ~A; the scenes are ~{~(~A~)~^, ~}~%" name (mapcar #'first scenes))
    (sb-ext:exit :code 1))
  (ensure-directories-exist out)
  (sb-ext:gc :full t)
  (let ((start (get-internal-real-time)))
    (multiple-value-bind (world recording)
        (funcall (find-symbol "RUN-PHYSICS-SCENE" '#:luv-physics) (first entry) :record t :every every)
      (declare (ignore world))
      (let ((recorded (get-internal-real-time)))
        (funcall (find-symbol "WRITE-PHYSICS-VIEWER" '#:luv-physics) recording out
                 :title (format nil "~(~A~): ~A" (first entry) (second entry)))
        (let ((written (get-internal-real-time))
              (frames (funcall (find-symbol "PHYSICS-RECORDING-FRAME-COUNT" '#:luv-physics) recording)))
          (format t "~&view: ~(~A~), ~D s at 60 Hz, a frame every ~D steps: ~D frames~%"
                  (first entry) (third entry) every frames)
          (format t "~&view: run and recorded in ~,2F s, written in ~,2F s: ~A, ~,1F MB~%"
                  (/ (- recorded start) internal-time-units-per-second)
                  (/ (- written recorded) internal-time-units-per-second)
                  out (/ (with-open-file (s out) (file-length s)) 1d6))
          (format t "~&view: open file://~A in a browser~%" (namestring (truename out))))))))
